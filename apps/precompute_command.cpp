// `kozu precompute microfacet-albedo -o FILE`: regenerates the directional-albedo tables that the
// `compensated` multiple-scattering mode and the plastic material use
// (src/materials/microfacet_albedo.h describes them). The integration is deterministic, so the
// checked-in file is reproduced bit for bit: scripts/test.sh does not run it, tests/materials checks
// the checked-in tables against fresh integrations at sample points.
#include "apps/command_errors.h"
#include "apps/commands.h"
#include "core/file_io.h"
#include "core/json_reader.h"
#include "materials/microfacet_albedo.h"
#include "render/output_paths.h"

#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

namespace kozu::app {

Command add_precompute_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("precompute", "Regenerate kozu's precomputed tables");
  cmd->require_subcommand(1);
  CLI::App* albedo = cmd->add_subcommand(
      "microfacet-albedo", "Directional albedo E(mu, alpha[, eta]) of GGX/Beckmann conductors and dielectrics");
  auto output = std::make_shared<std::string>();
  // The checked-in table's grid: the default reproduces it. Read as text and checked after parsing (a bad value is
  // exit status 1 naming the flag, not a usage error).
  auto grid_text = std::make_shared<std::string>("128");
  albedo->add_option("-o,--output", *output, "Output C++ include file (e.g. src/materials/microfacet_albedo_data.inc)")
      ->required();
  albedo->add_option("--grid", *grid_text, "Visible normals per table entry: N x N midpoint grid, N in [4, 4096]")
      ->capture_default_str();
  return [albedo, output, grid_text]() -> int {
    if (!albedo->parsed()) return 2;
    try {
      const auto grid =
          static_cast<int>(integer_flag_value(*grid_text, "kozu precompute", "--grid", Range::closed(4, 4096)));
      check_output(*output, "-o");  // before the integration, not after it
      const auto start = std::chrono::steady_clock::now();
      const std::string text = albedo::generate_tables(grid);
      write_file_atomic(*output, text);
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::fprintf(stderr, "%s: wrote microfacet albedo tables (%d x %d grid per entry) in %.1f s\n", output->c_str(),
                   grid, grid, seconds);
      return 0;
    } catch (const std::exception& e) {
      return report_failure("precompute", e);
    }
  };
}

}  // namespace kozu::app
