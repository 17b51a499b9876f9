// `kozu voxelize MESH.obj|.ply --resolution N -o OUT.kvox`: converts a triangle mesh into a voxel grid of area
// density and SGGX microflake matrices (src/tools/voxelize.h describes the conversion, src/media/voxel_grid.h the
// .kvox format), prints the grid and the memory of each MIP level, and writes the file atomically.
// Exit codes: 0 success, 1 a bad value, bad input or an output that cannot be written (checked before the mesh
// is read), 2 a usage error.
#include "apps/command_errors.h"
#include "apps/commands.h"
#include "core/error.h"
#include "core/file_io.h"
#include "core/json_reader.h"
#include "io/mesh_io.h"
#include "media/voxel_grid.h"
#include "render/output_paths.h"
#include "tools/voxelize.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

namespace kozu::app {

namespace {

std::string format_bytes(size_t bytes) {
  if (bytes >= (size_t{1} << 20)) return fmt::format("{:.2f} MiB", double(bytes) / double(1 << 20));
  if (bytes >= (size_t{1} << 10)) return fmt::format("{:.2f} KiB", double(bytes) / double(1 << 10));
  return fmt::format("{} B", bytes);
}

int run_voxelize(const std::string& mesh_path, int resolution, const std::string& output, bool float_storage) {
  const auto start = std::chrono::steady_clock::now();
  VoxelGrid grid;
  VoxelizeStats stats;
  const MeshData mesh = load_mesh(mesh_path);
  try {
    grid = voxelize_mesh(mesh, resolution, &stats);
  } catch (const std::invalid_argument& e) {
    throw InputError(mesh_path, "", e.what());
  }
  const double voxelize_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!float_storage) grid.compact();  // .kvox version 2 (media store it so anyway)
  grid.save_kvox(output);

  const Vec3i r = grid.resolution();
  const Vec3 h = grid.voxel_size();
  std::printf("%s: %zu triangles, area %.6g\n", mesh_path.c_str(), stats.triangles, stats.mesh_area);
  std::printf("resolution %d x %d x %d, voxel size %.6g, box (%.6g, %.6g, %.6g) - (%.6g, %.6g, %.6g)\n", r.x, r.y, r.z,
              double(h.x), double(grid.lo().x), double(grid.lo().y), double(grid.lo().z), double(grid.hi().x),
              double(grid.hi().y), double(grid.hi().z));
  std::printf("voxels %zu, occupied %zu (%.2f%%), pieces %zu, deposited area %.6g (relative error %.2e)\n",
              grid.voxel_count(), stats.occupied_voxels,
              100.0 * double(stats.occupied_voxels) / double(grid.voxel_count()), stats.pieces, stats.deposited_area,
              std::abs(stats.deposited_area - stats.mesh_area) / stats.mesh_area);
  const std::vector<VoxelGrid> chain = build_mip_chain(grid);
  size_t total = 0;
  for (size_t level = 0; level < chain.size(); ++level) {
    const VoxelGrid& g = chain[level];
    size_t occupied = 0;
    for (size_t idx = 0; idx < g.voxel_count(); ++idx) occupied += g.density_at(idx) > 0.0f ? 1 : 0;
    total += g.memory_bytes();
    std::printf("  MIP %2zu: %4d x %4d x %4d, %10zu voxels, %10zu occupied, %s\n", level, g.resolution().x,
                g.resolution().y, g.resolution().z, g.voxel_count(), occupied, format_bytes(g.memory_bytes()).c_str());
  }
  std::printf("  all levels: %s\n", format_bytes(total).c_str());
  std::fflush(stdout);
  std::fprintf(stderr, "%s: wrote %d x %d x %d voxels in %.2f s (voxelization %.2f s)\n", output.c_str(), r.x, r.y, r.z,
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), voxelize_s);
  return 0;
}

}  // namespace

Command add_voxelize_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "voxelize", "Convert a triangle mesh (.obj or .ply) into a .kvox grid of area density and SGGX matrices");
  auto mesh_path = std::make_shared<std::string>();
  auto output = std::make_shared<std::string>();
  // Read as text and checked after parsing, by the rule of scene keys: a bad value is exit status 1 naming the
  // flag; CLI11's validators would make it a usage error (2).
  auto resolution_text = std::make_shared<std::string>("64");
  cmd->add_option("mesh", *mesh_path, "Input mesh (.obj or .ply)")->required();
  cmd->add_option("-o,--output", *output, "Output voxel grid (.kvox)")->required();
  cmd->add_option("-r,--resolution", *resolution_text,
                  "Voxels along the mesh's longest axis, in [4, 1024] (cubic voxels)")
      ->capture_default_str();
  auto float_storage = std::make_shared<bool>(false);
  cmd->add_flag("--float", *float_storage,
                "Write .kvox version 1 (32-bit floats, exact) instead of the compact version 2 (16-bit density, "
                "6-byte SGGX)");
  return [cmd, mesh_path, output, resolution_text, float_storage]() -> int {
    if (!cmd->parsed()) return 2;
    try {
      const auto resolution = static_cast<int>(
          integer_flag_value(*resolution_text, "kozu voxelize", "--resolution", Range::closed(4, 1024)));
      if (lower_extension(*output) != ".kvox")
        throw std::runtime_error(fmt::format("-o {}: the output must be a .kvox file", *output));
      // Before the mesh is read and voxelized, not after; the mesh is an input that -o must not overwrite.
      check_output(*output, "-o", {*mesh_path});
      return run_voxelize(*mesh_path, resolution, *output, *float_storage);
    } catch (const std::exception& e) {
      return report_failure("voxelize", e);
    }
  };
}

}  // namespace kozu::app
