// `kozu procedural smoke|yarn|fabric -o OUT.kvox [--resolution N]`: generates one of kozu's procedural volumes
// (src/media/procedural_volume.h: a smoke plume of density, a ball of twisted 2-ply yarn, or a plain-weave
// fabric patch, the last two with fiber-like SGGX matrices), writes it atomically as .kvox — or, for the smoke,
// as OpenVDB (`-o smoke.vdb`, the file Blender and bench/cycles read) — and prints one summary line. Default resolutions: smoke 64, yarn 192, fabric 384.
// Exit codes: 0 success, 1 a bad value, a bad output name or an output that cannot be written (checked before the
// generation), 2 a usage error.
#include "apps/command_errors.h"
#include "apps/commands.h"
#include "core/file_io.h"
#include "core/json_reader.h"
#include "media/voxel_grid.h"
#include "render/output_paths.h"
#include "media/procedural_volume.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

namespace kozu::app {

namespace {

int run_procedural(const std::string& kind_text, const std::optional<std::string>& resolution_text,
                   const std::string& output, bool float_storage) {
  const std::string command = "kozu procedural";
  const std::string kind = choice_flag_value(kind_text, command, "the volume", {"smoke", "yarn", "fabric"});
  const ProceduralVolumeKind& gen = *find_procedural_volume(kind);
  const int n =
      !resolution_text
          ? gen.default_resolution
          : static_cast<int>(integer_flag_value(*resolution_text, command, "--resolution",
                                                Range::closed(procedural::kMinResolution, procedural::kMaxResolution)));
  const bool vdb = lower_extension(output) == ".vdb";
  if (!vdb && lower_extension(output) != ".kvox")
    throw std::runtime_error(fmt::format("-o {}: the output must be a .kvox or .vdb file", output));
  if (vdb && kind != "smoke")
    throw std::runtime_error(
        fmt::format("-o {}: the {} has SGGX matrices, which OpenVDB files cannot hold: write .kvox", output, kind));
  check_output(output, "-o");  // before the generation, not after it
  const auto start = std::chrono::steady_clock::now();
  VoxelGrid grid = gen.make(n);
  const double generate_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
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
                 kind.c_str(),
                 enough ? fmt::format(" (use at least {})", enough).c_str()
                        : fmt::format(" (the default is {})", gen.default_resolution).c_str());
    return 1;
  }
  if (vdb) {
    grid.save_vdb(output);
  } else {
    if (!float_storage) grid.compact();  // .kvox version 2 (media store it so anyway)
    grid.save_kvox(output);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const Vec3i r = grid.resolution();
  std::printf(
      "%s: %s %d x %d x %d, occupied %zu of %zu voxels (%.2f%%), %s, memory %.2f MiB, %.2f s (generation %.2f s)\n",
      output.c_str(), kind.c_str(), r.x, r.y, r.z, occupied, grid.voxel_count(),
      100.0 * double(occupied) / double(grid.voxel_count()), grid.has_sggx() ? "density + SGGX" : "density",
      double(grid.memory_bytes()) / double(1 << 20), seconds, generate_s);
  return 0;
}

}  // namespace

Command add_procedural_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "procedural",
      "Generate a procedural volume as .kvox: smoke (density; also .vdb), yarn or fabric (density and SGGX)");
  // Values are read as text and checked after parsing, by the rules of scene keys: a bad value is exit status 1
  // with one message naming it; CLI11's validators would make it a usage error (2).
  auto kind = std::make_shared<std::string>();
  auto output = std::make_shared<std::string>();
  auto resolution_text = std::make_shared<std::optional<std::string>>();
  auto float_storage = std::make_shared<bool>(false);
  cmd->add_option("kind", *kind, "Volume: smoke, yarn or fabric")->required();
  cmd->add_option("-o,--output", *output, "Output voxel grid (.kvox; .vdb for the smoke)")->required();
  cmd->add_option("-r,--resolution", *resolution_text,
                  fmt::format("Voxels along x, in [{}, {}] (default: smoke 64, yarn 192, fabric 384; cubic voxels)",
                              procedural::kMinResolution, procedural::kMaxResolution));
  cmd->add_flag("--float", *float_storage,
                "Write .kvox version 1 (32-bit floats, exact) instead of the compact version 2 (16-bit density, "
                "6-byte SGGX)");
  return [cmd, kind, output, resolution_text, float_storage]() -> int {
    if (!cmd->parsed()) return 2;
    try {
      return run_procedural(*kind, *resolution_text, *output, *float_storage);
    } catch (const std::exception& e) {
      return report_failure("procedural", e);
    }
  };
}

}  // namespace kozu::app
