// Memory checks before meshes, their hierarchy and instances are allocated: the estimates from counts, and
// refusals under a KOZU_MEMORY_LIMIT just below them (the same files load without the limit).
#include "io/mesh_io.h"

#include "core/error.h"
#include "core/file_io.h"
#include "core/memory.h"
#include "geometry/embree_scene.h"
#include "scene/scene_loader.h"
#include "support/memory_limit_env.h"
#include "support/render_test.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>
#include <string>

namespace kozu {
namespace {

namespace fs = std::filesystem;

// A limit that leaves `left` bytes beyond what the process holds now.
size_t limit_leaving(double left) { return current_rss_bytes() + size_t(left); }

// An n x n grid of quads (OBJ, 1-based) or triangles (binary PLY).
std::string grid_obj(int n) {
  std::string s;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) s += fmt::format("v {} 0 {}\n", i, j);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i + 1;
      s += fmt::format("f {} {} {} {}\n", a, a + 1, a + n + 2, a + n + 1);
    }
  return s;
}

std::string grid_ply(int n) {
  std::string s = fmt::format(
      "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float "
      "z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
      (n + 1) * (n + 1), 2 * n * n);
  const auto put = [&](const auto& v) { s.append(reinterpret_cast<const char*>(&v), sizeof v); };
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      for (const float c : {float(i), 0.0f, float(j)}) put(c);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      s += char(3);
      for (const int v : {a, b, c}) put(v);
      s += char(3);
      for (const int v : {a, c, d}) put(v);
    }
  return s;
}

TEST(MeshMemory, CountObjStatements) {
  // Blanks before keywords, \r\n and lone \r line ends, a pentagon (3 triangles), runs split by g and usemtl.
  const std::string text =
      "# comment v 1 2 3\nv 0 0 0\r\n  v 1 0 0\rv 1 1 0\nv 0 1 0\nv 2 2 0\nvt 0 0\nvt 1 1\nvn 0 0 1\n"
      "f 1 2 3\nf 1 2 3 4 5\ng part\nusemtl red\nf 1/1/1 2/2/1 3/1/1 4/2/1\nf\t1 2 3\nvp 1 2\nfo 1 2 3\n";
  const MeshCounts c = count_obj(text);
  EXPECT_EQ(c.text_bytes, text.size());
  EXPECT_EQ(c.positions, 5u);
  EXPECT_EQ(c.texcoords, 2u);
  EXPECT_EQ(c.normals, 1u);
  EXPECT_EQ(c.triangles, 1u + 3u + 2u + 1u);
  EXPECT_TRUE(c.usemtl);
  EXPECT_EQ(c.run_faces, 2u);  // the first run: 2 faces, 8 corners; the last: 2 faces, 7 corners
  EXPECT_EQ(c.run_corners, 8u);
  EXPECT_FALSE(count_obj("v 0 0 0\nf 1 1 1\n").usemtl);
}

TEST(MeshMemory, EstimatesFollowTheCounts) {
  // A 200 x 200 quad grid: 40,401 positions, 80,000 triangles in one run of 40,000 faces with 160,000 corners.
  const std::string text = grid_obj(200);
  const MeshCounts c = count_obj(text);
  EXPECT_EQ(c.positions, 40401u);
  EXPECT_EQ(c.triangles, 80000u);
  EXPECT_EQ(c.run_faces, 40000u);
  EXPECT_EQ(c.run_corners, 160000u);
  // The parse is the peak: the text's copy, 32 bytes a position, 80 a face, 12 a corner, 90 a triangle.
  const double parse = double(text.size()) + 32.0 * 40401 + 80.0 * 40000 + 12.0 * 160000 + 90.0 * 80000;
  EXPECT_DOUBLE_EQ(obj_memory_bytes(c), parse);
  // usemtl makes a second copy of the text; splitting the faces into runs lowers the estimate.
  MeshCounts u = c;
  u.usemtl = true;
  EXPECT_DOUBLE_EQ(obj_memory_bytes(u), parse + double(text.size()));
  MeshCounts runs = c;
  runs.run_faces = 200;
  runs.run_corners = 800;
  EXPECT_LT(obj_memory_bytes(runs), obj_memory_bytes(c));
  // PLY: kozu's arrays only (24 bytes a vertex with the padding vertex's move, 12 a triangle, more with attributes).
  MeshCounts p;
  p.positions = 1000;
  p.triangles = 2000;
  EXPECT_DOUBLE_EQ(ply_memory_bytes(p), 24.0 * 1000 + 12.0 * 2000);
  p.normals = p.texcoords = 1000;
  EXPECT_DOUBLE_EQ(ply_memory_bytes(p), 24.0 * 1000 + 12.0 * 2000 + 20.0 * 1000);
  // Measured on a 1000 x 1000 quad grid: a parse peak of 376 MB; the estimate is a little above.
  MeshCounts big;
  big.text_bytes = 41374027;
  big.positions = 1002001;
  big.triangles = 2000000;
  big.run_faces = 1000000;
  big.run_corners = 4000000;
  EXPECT_GT(obj_memory_bytes(big), 376e6);
  EXPECT_LT(obj_memory_bytes(big), 1.1 * 376e6);
}

// Loads `file` (or parses `data` as it, when given) expecting the memory refusal that names it.
void expect_refused(const fs::path& file, uint64_t triangles, std::optional<std::string_view> data = {}) {
  try {
    const MeshData mesh = data ? parse_ply(file, *data) : load_mesh(file);
    ADD_FAILURE() << "expected a refusal, loaded " << mesh.indices.size() / 3 << " triangles";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.file(), file.string());
    EXPECT_NE(what.find("the mesh needs about "), std::string::npos) << what;
    EXPECT_NE(what.find(fmt::format("({} triangles) but only ", triangles)), std::string::npos) << what;
    EXPECT_NE(what.find("limit (KOZU_MEMORY_LIMIT) is left"), std::string::npos) << what;
  }
}

TEST(MeshMemory, ObjRefusedBelowItsEstimateAndLoadedWithout) {
  test::TempDir dir;
  const std::string text = grid_obj(200);
  const fs::path file = dir.write("grid.obj", text);
  const double need = obj_memory_bytes(count_obj(text));
  {
    // The file itself fits (read before the check); the parse does not.
    const test::MemoryLimitEnv limit(limit_leaving(double(text.size()) + 0.5 * (need - double(text.size()))));
    expect_refused(file, 80000);
  }
  {
    const test::MemoryLimitEnv limit(limit_leaving(double(text.size()) + 2.0 * need));
    EXPECT_EQ(load_mesh(file).indices.size(), 3u * 80000);
  }
  const test::MemoryLimitEnv none(0);
  EXPECT_EQ(load_mesh(file).indices.size(), 3u * 80000);
}

TEST(MeshMemory, PlyRefusedBelowItsEstimateAndLoadedWithout) {
  test::TempDir dir;
  const std::string data = grid_ply(200);
  const fs::path file = dir.write("grid.ply", data);
  MeshCounts c;
  c.positions = 201 * 201;
  c.triangles = 80000;
  const double need = ply_memory_bytes(c);
  {
    // Parsed from the bytes in memory: the small file's own read could reuse freed memory and blur the limit.
    const test::MemoryLimitEnv limit(limit_leaving(0.3 * need));
    expect_refused(file, 80000, data);
  }
  const test::MemoryLimitEnv none(0);
  EXPECT_EQ(load_mesh(file).indices.size(), 3u * 80000);
}

TEST(MeshMemory, SceneMessageNamesSceneAndMesh) {
  test::TempDir dir;
  const std::string text = grid_obj(200);
  dir.write("grid.obj", text);
  const fs::path scene = dir.write("scene.json", R"({
    "camera": {"position": [100, 50, -100], "look_at": [100, 0, 100], "fov": 40, "resolution": [8, 8]},
    "materials": {"m": {"type": "diffuse", "albedo": 0.5}},
    "shapes": [{"type": "mesh", "file": "grid.obj", "material": "m"}],
    "lights": [{"type": "environment", "radiance": 1}] })");
  const double need = obj_memory_bytes(count_obj(text));
  {
    const test::MemoryLimitEnv limit(limit_leaving(double(text.size()) + 0.5 * (need - double(text.size()))));
    try {
      load_scene_file(scene);
      ADD_FAILURE() << "expected a refusal";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("scene.json: /shapes/0/file: "), std::string::npos) << what;
      EXPECT_NE(what.find("grid.obj: the mesh needs about "), std::string::npos) << what;
    }
  }
  const test::MemoryLimitEnv none(0);
  EXPECT_EQ(load_scene_file(scene)->triangle_count(), 80000u);
}

TEST(MeshMemory, HierarchyRefusedBelowItsEstimate) {
  MeshData grid = parse_obj("grid.obj", grid_obj(200));
  std::vector<std::unique_ptr<Shape>> shapes;
  shapes.push_back(std::make_unique<TriangleMesh>(std::move(grid.positions), std::move(grid.indices)));
  {
    // 80,000 triangles need about 8 MB of hierarchy.
    const test::MemoryLimitEnv limit(limit_leaving(2e6));
    try {
      EmbreeScene scene(shapes);
      ADD_FAILURE() << "expected a refusal";
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("the scene's acceleration structure needs about 8 MiB (80000 primitives, 0 instances)"),
                std::string::npos)
          << what;
      EXPECT_NE(what.find("limit (KOZU_MEMORY_LIMIT) is left"), std::string::npos) << what;
    }
  }
  const test::MemoryLimitEnv none(0);
  EmbreeScene scene(shapes);
  SurfaceInteraction si;
  EXPECT_TRUE(scene.intersect(Ray{Vec3(10.5f, 1.0f, 10.5f), Vec3(0, -1, 0), kInfinity}, si));
}

TEST(MeshMemory, InstancesRefusedBelowTheirEstimate) {
  {
    const test::MemoryLimitEnv limit(limit_leaving(4e6));
    try {
      check_instance_memory(100000, "scene.json", "/shapes");
      ADD_FAILURE() << "expected a refusal";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("scene.json: /shapes: the scene's 100000 instances need about "), std::string::npos) << what;
    }
    EXPECT_NO_THROW(check_instance_memory(100, "scene.json", "/shapes"));
  }
  const test::MemoryLimitEnv none(0);
  EXPECT_NO_THROW(check_instance_memory(100000, "scene.json", "/shapes"));
}

TEST(MeshMemory, CornellLoadsUnderAReasonableLimit) {
  const test::MemoryLimitEnv limit(limit_leaving(512.0 * 1024 * 1024));
  const auto scene = load_scene_text(read_input_file(test::source_dir() / "scenes/cornell.json"), "cornell.json",
                                     test::source_dir() / "scenes");
  EXPECT_GT(scene->shapes.size(), 0u);
}

}  // namespace
}  // namespace kozu
