// kozu: command-line entry point. `kozu render ...` renders a scene; see `kozu render --help`.
#include "apps/commands.h"
#include "core/json_reader.h"
#include "core/version.h"
#ifdef KOZU_HAVE_MPI
#include "apps/mpi_world.h"
#endif

#include <OpenImageIO/oiioversion.h>
#include <embree3/rtcore_config.h>
#include <fmt/format.h>
#include <oneapi/tbb/version.h>

#include <cstdio>

namespace kozu::app {

CLI::Validator decimal_integer() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        const Json v = flag_value(s);
        if (!v.is_number_integer() && !v.is_number_unsigned()) return "expected a decimal integer, got '" + s + "'";
        s = v.dump();  // without leading zeros
        return {};
      },
      "INT");
}

}  // namespace kozu::app

int main(int argc, char** argv) {
#ifdef KOZU_HAVE_MPI
  // Under mpirun: MPI for the whole run (render splits its tiles across the ranks); otherwise nothing.
  kozu::app::MpiWorld mpi(&argc, &argv);
#endif
  CLI::App app{"kozu: a physically based path tracer", "kozu"};
  app.set_version_flag("--version",
                       fmt::format("kozu {} ({}, Embree {}.{}.{}, oneTBB {}.{}, OpenImageIO {})", KOZU_VERSION,
                                   KOZU_BUILD_TYPE, RTC_VERSION_MAJOR, RTC_VERSION_MINOR, RTC_VERSION_PATCH,
                                   TBB_VERSION_MAJOR, TBB_VERSION_MINOR, OIIO_VERSION_STRING));
  app.require_subcommand(1);
  app.fallthrough();
  kozu::app::Command render = kozu::app::add_render_command(app);
  kozu::app::Command precompute = kozu::app::add_precompute_command(app);
  kozu::app::Command sss_reference = kozu::app::add_sss_reference_command(app);
  kozu::app::Command voxelize = kozu::app::add_voxelize_command(app);
  kozu::app::Command procedural = kozu::app::add_procedural_command(app);
  kozu::app::Command maketx = kozu::app::add_maketx_command(app);
  kozu::app::Command fit_ltc = kozu::app::add_fit_ltc_command(app);
  kozu::app::Command merge = kozu::app::add_merge_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    // Help and --version are successes; usage errors exit with 2.
    return code == 0 ? 0 : 2;
  }
  // Every command reports its own errors; this is the last line of defence, so that no input ends in an
  // uncaught exception (an abort) rather than one message and exit status 1.
  try {
    if (app.got_subcommand("render")) return render();
    if (app.got_subcommand("precompute")) return precompute();
    if (app.got_subcommand("sss-reference")) return sss_reference();
    if (app.got_subcommand("voxelize")) return voxelize();
    if (app.got_subcommand("procedural")) return procedural();
    if (app.got_subcommand("maketx")) return maketx();
    if (app.got_subcommand("fit-ltc")) return fit_ltc();
    if (app.got_subcommand("merge")) return merge();
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "error: kozu: out of memory\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: kozu: %s\n", e.what());
    return 1;
  }
  return 2;
}
