// kozu: command-line entry point. `kozu render ...` renders a scene; see `kozu render --help`.
#include "apps/commands.h"
#include "apps/stop_signals.h"
#include "core/json_reader.h"
#include "core/version.h"
#ifdef KOZU_HAVE_MPI
#include "apps/mpi_world.h"
#endif

#include <OpenImageIO/oiioversion.h>
#include <embree3/rtcore_config.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <oneapi/tbb/version.h>

#include <algorithm>
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

namespace {

// The one-line message of a usage error (CLI11's, made precise: the unknown option or command and the closest one);
// *where: the command that was parsed ("kozu", "kozu render", "kozu texture filter-normals").
std::string usage_error(const CLI::App& app, const CLI::ParseError& e, const std::vector<std::string>& commands,
                        std::string* where) {
  const std::vector<CLI::App*> parsed = app.get_subcommands();
  const CLI::App* sub = parsed.empty() ? &app : parsed.front();
  *where = parsed.empty() ? "kozu" : "kozu " + sub->get_name();
  // A command group (kozu texture filter-normals): the innermost command that was parsed names the error.
  while (!sub->get_subcommands().empty()) {
    sub = sub->get_subcommands().front();
    *where += " " + sub->get_name();
  }
  std::string message = e.what();
  if (parsed.empty() && dynamic_cast<const CLI::RequiredError*>(&e))
    message = fmt::format("a command is required: {}", fmt::join(commands, ", "));
  // An argument nobody took explains any error best (a misspelt required option is also "missing"): an option
  // gets the closest one of its command.
  std::vector<std::string> extras = sub->remaining();
  if (extras.empty()) extras = app.remaining();
  const auto option = std::find_if(extras.begin(), extras.end(), [](const std::string& w) { return w[0] == '-'; });
  if (option != extras.end()) {
    std::vector<std::string> names;
    for (const CLI::Option* o : sub->get_options()) {
      for (const std::string& n : o->get_lnames()) names.push_back("--" + n);
      for (const std::string& n : o->get_snames()) names.push_back("-" + n);
    }
    const std::string bare = option->substr(0, option->find('='));
    const std::string best = bare.size() > 2 ? kozu::closest_match(bare, names) : "";  // not for -x
    message = fmt::format("unknown option '{}'{}", kozu::text_excerpt(bare),
                          best.empty() ? "" : fmt::format(" (did you mean '{}'?)", best));
  } else if (!parsed.empty() && !sub->get_subcommands({}).empty() && dynamic_cast<const CLI::RequiredError*>(&e)) {
    // A command group without (or with a misspelt) command: name its commands, and the closest one.
    std::vector<std::string> names;
    for (const CLI::App* c : sub->get_subcommands({})) names.push_back(c->get_name());
    if (extras.empty()) {
      message = fmt::format("a command is required: {}", fmt::join(names, ", "));
    } else {
      const std::string best = kozu::closest_match(extras.front(), names);
      message = fmt::format("unknown command '{}'{}; the commands: {}", kozu::text_excerpt(extras.front()),
                            best.empty() ? "" : fmt::format(" (did you mean '{}'?)", best), fmt::join(names, ", "));
    }
  } else if (dynamic_cast<const CLI::ExtrasError*>(&e) && !extras.empty()) {
    message = fmt::format("unexpected argument '{}'", kozu::text_excerpt(extras.front()));
  }
  return message;
}

// The full name of the command app parsed ("kozu texture height").
std::string parsed_command_name(const CLI::App& app) {
  std::string name = "kozu";
  for (const CLI::App* c = &app; !c->get_subcommands().empty();) {
    c = c->get_subcommands().front();
    name += " " + c->get_name();
  }
  return name;
}

}  // namespace

}  // namespace kozu::app

int main(int argc, char** argv) {
#ifdef KOZU_HAVE_MPI
  // Under mpirun: MPI for the whole run (render splits its tiles across the ranks); otherwise nothing.
  kozu::app::MpiWorld mpi(&argc, &argv);
#endif
  // Every command stops within moments of SIGINT/SIGTERM/SIGHUP and leaves no partial file (apps/stop_signals.h).
  kozu::app::StopSignals::install();
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
  kozu::app::Command fit_rational = kozu::app::add_fit_rational_command(app);
  kozu::app::Command cod_diffuse_reference = kozu::app::add_cod_diffuse_reference_command(app);
  kozu::app::Command merge = kozu::app::add_merge_command(app);
  kozu::app::Command texture = kozu::app::add_texture_command(app);
  // A first word that is not an option must be a command: name it, and the closest one (CLI11 would only say that
  // the argument was not expected).
  std::vector<std::string> commands;
  for (const CLI::App* c : app.get_subcommands({})) commands.push_back(c->get_name());
  if (argc > 1 && argv[1][0] != '-') {
    if (std::find(commands.begin(), commands.end(), argv[1]) == commands.end()) {
      const std::string best = kozu::closest_match(argv[1], commands);
      std::fprintf(stderr, "error: unknown command '%s'%s; the commands: %s (kozu --help)\n",
                   kozu::text_excerpt(argv[1]).c_str(),
                   best.empty() ? "" : fmt::format(" (did you mean '{}'?)", best).c_str(),
                   fmt::format("{}", fmt::join(commands, ", ")).c_str());
      return 2;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // Help and --version are successes (CLI11 prints them); usage errors are one line of kozu's own, exit 2.
    if (e.get_exit_code() == 0) return app.exit(e);
    std::string where;
    const std::string message = kozu::app::usage_error(app, e, commands, &where);
    std::fprintf(stderr, "error: %s: %s (%s --help)\n", where.c_str(), message.c_str(), where.c_str());
#ifdef KOZU_HAVE_MPI
    // Ranks whose command line did parse wait for this one at the render's first agreement: take part in it as a
    // failed rank, so they stop too (apps/mpi_world.h).
    if (mpi.distributed() && argc > 1 && std::string(argv[1]) == "render") mpi.agree(2, 0);
#endif
    return 2;
  }
  // Every command reports its own errors; this is the last line of defence, so that no input ends in an
  // uncaught exception (an abort) rather than one message and exit status 1.
  kozu::app::StopSignals::set_command(kozu::app::parsed_command_name(app));
  try {
    if (app.got_subcommand("render")) return render();
    if (app.got_subcommand("precompute")) return precompute();
    if (app.got_subcommand("sss-reference")) return sss_reference();
    if (app.got_subcommand("voxelize")) return voxelize();
    if (app.got_subcommand("procedural")) return procedural();
    if (app.got_subcommand("maketx")) return maketx();
    if (app.got_subcommand("fit-ltc")) return fit_ltc();
    if (app.got_subcommand("fit-rational")) return fit_rational();
    if (app.got_subcommand("cod-diffuse-reference")) return cod_diffuse_reference();
    if (app.got_subcommand("merge")) return merge();
    if (app.got_subcommand("texture")) return texture();
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "error: kozu: out of memory\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: kozu: %s\n", e.what());
    return 1;
  }
  return 2;
}
