// `kozu precompute microfacet-albedo -o FILE`: regenerates the directional-albedo tables that the
// `compensated` multiple-scattering mode and the plastic material use
// (src/materials/microfacet_albedo.h describes them). The integration is deterministic, so the
// checked-in file is reproduced bit for bit: scripts/test.sh does not run it, tests/materials checks
// the checked-in tables against fresh integrations at sample points.
#include "apps/commands.h"
#include "core/file_io.h"
#include "materials/microfacet_albedo.h"

#include <fmt/format.h>

#include <chrono>
#include <cstdio>

namespace kozu::app {

Command add_precompute_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("precompute", "Regenerate kozu's precomputed tables");
  cmd->require_subcommand(1);
  CLI::App* albedo = cmd->add_subcommand(
      "microfacet-albedo", "Directional albedo E(mu, alpha[, eta]) of GGX/Beckmann conductors and dielectrics");
  auto output = std::make_shared<std::string>();
  auto grid = std::make_shared<int>(128);  // the checked-in table's grid: the default reproduces it
  albedo->add_option("-o,--output", *output, "Output C++ include file (e.g. src/materials/microfacet_albedo_data.inc)")
      ->required();
  albedo->add_option("--grid", *grid, "Visible normals per table entry: N x N midpoint grid")
      ->transform(decimal_integer())
      ->check(CLI::Range(4, 4096))
      ->capture_default_str();
  return [albedo, output, grid]() -> int {
    if (!albedo->parsed()) return 2;
    const auto start = std::chrono::steady_clock::now();
    const std::string text = albedo::generate_tables(*grid);
    try {
      write_file_atomic(*output, text);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "kozu precompute: %s\n", e.what());
      return 1;
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::fprintf(stderr, "%s: wrote microfacet albedo tables (%d x %d grid per entry) in %.1f s\n", output->c_str(),
                 *grid, *grid, seconds);
    return 0;
  };
}

}  // namespace kozu::app
