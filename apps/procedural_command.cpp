// `kozu procedural smoke|yarn|fabric -o OUT.kvox [--resolution N]`: generates one of kozu's procedural volumes
// (src/tools/procedural_volume.h: a smoke plume of density, a ball of twisted 2-ply yarn, or a plain-weave
// fabric patch, the last two with fiber-like SGGX matrices), writes it atomically as .kvox and prints one
// summary line. Default resolutions: smoke 64, yarn 192, fabric 384.
// Exit codes: 0 success, 1 bad output name or failure to write.
#include "apps/commands.h"
#include "core/file_io.h"
#include "media/voxel_grid.h"
#include "tools/procedural_volume.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <string>

namespace kozu::app {

namespace {

struct Generator {
  VoxelGrid (*make)(int);
  int default_resolution;
};

const std::map<std::string, Generator>& generators() {
  static const std::map<std::string, Generator> table = {
      {"smoke", {make_smoke_plume, 64}},
      {"yarn", {make_yarn_ball, 192}},
      {"fabric", {make_woven_fabric, 384}},
  };
  return table;
}

}  // namespace

Command add_procedural_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "procedural", "Generate a procedural volume as .kvox: smoke (density), yarn or fabric (density and SGGX)");
  auto kind = std::make_shared<std::string>();
  auto output = std::make_shared<std::string>();
  auto resolution = std::make_shared<int>(0);
  cmd->add_option("kind", *kind, "Volume: smoke, yarn or fabric")
      ->required()
      ->check(CLI::IsMember({"smoke", "yarn", "fabric"}));
  cmd->add_option("-o,--output", *output, "Output voxel grid (.kvox)")->required();
  cmd->add_option("-r,--resolution", *resolution,
                  "Voxels along x (default: smoke 64, yarn 192, fabric 384; cubic voxels)")
      ->transform(decimal_integer())
      ->check(CLI::Range(procedural::kMinResolution, procedural::kMaxResolution));
  return [cmd, kind, output, resolution]() -> int {
    if (!cmd->parsed()) return 2;
    if (lower_extension(*output) != ".kvox") {
      std::fprintf(stderr, "kozu procedural: %s: the output must be a .kvox file\n", output->c_str());
      return 1;
    }
    const Generator& gen = generators().at(*kind);
    const int n = *resolution > 0 ? *resolution : gen.default_resolution;
    const auto start = std::chrono::steady_clock::now();
    VoxelGrid grid;
    double generate_s = 0.0;
    try {
      grid = gen.make(n);
      generate_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "kozu procedural: %s\n", e.what());
      return 1;
    }
    const auto occupied_voxels = [](const VoxelGrid& g) {
      size_t count = 0;
      for (float d : g.density_data()) count += d > 0.0f ? 1 : 0;
      return count;
    };
    const size_t occupied = occupied_voxels(grid);
    if (occupied == 0) {
      // Threads thinner than a voxel fall between the samples: name the smallest resolution that holds some
      // (searched in steps of 8, cheap at these sizes), and write nothing.
      int enough = 0;
      for (int m = n + 8; m <= gen.default_resolution && !enough; m += 8)
        if (occupied_voxels(gen.make(m)) > 0) enough = m;
      std::fprintf(stderr,
                   "error: kozu procedural: --resolution %d is too small to hold the %s: no voxel is occupied%s\n", n,
                   kind->c_str(),
                   enough ? fmt::format(" (use at least {})", enough).c_str()
                          : fmt::format(" (the default is {})", gen.default_resolution).c_str());
      return 1;
    }
    try {
      grid.save_kvox(*output);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "kozu procedural: %s\n", e.what());
      return 1;
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const Vec3i r = grid.resolution();
    std::printf(
        "%s: %s %d x %d x %d, occupied %zu of %zu voxels (%.2f%%), %s, memory %.2f MiB, %.2f s (generation %.2f s)\n",
        output->c_str(), kind->c_str(), r.x, r.y, r.z, occupied, grid.voxel_count(),
        100.0 * double(occupied) / double(grid.voxel_count()), grid.has_sggx() ? "density + SGGX" : "density",
        double(grid.memory_bytes()) / double(1 << 20), seconds, generate_s);
    return 0;
  };
}

}  // namespace kozu::app
