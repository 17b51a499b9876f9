// OBJ usemtl groups (io/mesh_io.h MeshData::groups) and "materials_by_name" (docs/scene-format.md#mesh): each face
// takes the scene material its usemtl names, faces before the first usemtl the shape's "material"; a name the
// scene does not define, or a missing default, is an error naming the shape.
#include "core/error.h"
#include "geometry/mesh_cleanup.h"
#include "io/mesh_io.h"
#include "scene/scene_loader.h"
#include "support/render_test.h"

#include <gtest/gtest.h>

#include <map>
#include <string>

namespace kozu {
namespace {

using test::TempDir;

// A triangle before any usemtl, a quad (2 triangles) of "blue", a zero-area triangle of "red", a triangle of
// "red", and one more "blue" triangle after it.
constexpr const char* kObj = R"(mtllib scene.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 2 0 0
v 2 1 0
f 1 2 3
usemtl blue
f 1 2 3 4
usemtl red
f 1 1 2
f 2 5 6
usemtl blue
f 2 6 3
)";

TEST(ObjUsemtl, GroupsFollowTheFacesThroughTriangulationAndCleanup) {
  MeshData m = parse_obj("t.obj", kObj);
  ASSERT_EQ(m.indices.size(), 6u * 3);
  ASSERT_EQ(m.groups.size(), 6u);
  const std::vector<std::string> names = {"", "blue", "red"};
  EXPECT_EQ(m.group_names, names);
  EXPECT_EQ(m.groups, (std::vector<uint32_t>{0, 1, 1, 2, 2, 1}));
  EXPECT_EQ(remove_degenerate_triangles(m), 1u);
  EXPECT_EQ(m.groups, (std::vector<uint32_t>{0, 1, 1, 2, 1}));
  // A file without usemtl has no groups.
  EXPECT_TRUE(parse_obj("t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").groups.empty());
}

std::string scene_json(const std::string& materials, const std::string& shape_keys) {
  return R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "resolution": [8, 8]},
    "materials": {)" +
         materials + R"(},
    "shapes": [{"type": "mesh", "file": "m.obj", "materials_by_name": true, "skip_degenerate": true)" +
         shape_keys + R"(}], "lights": [{"type": "environment", "radiance": 1}]})";
}

std::string load_error(const TempDir& dir, const std::string& json) {
  try {
    load_scene_file(dir.write("s.json", json));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(ObjUsemtl, MaterialsByNameSplitTheMeshByMaterial) {
  TempDir dir;
  dir.write("m.obj", kObj);
  const std::string three = R"("red": {"type": "diffuse"}, "blue": {"type": "diffuse"}, "white": {"type": "diffuse"})";
  const auto scene = load_scene_file(dir.write("s.json", scene_json(three, R"(, "material": "white")")));
  std::map<std::string, size_t> triangles;
  for (const auto& s : scene->shapes) triangles[s->material->name] += s->primitive_count();
  EXPECT_EQ(triangles, (std::map<std::string, size_t>{{"white", 1}, {"blue", 3}, {"red", 1}}));
  const std::string s = dir.path().string() + "/s.json";
  EXPECT_EQ(load_error(dir, scene_json(three, "")),
            s + ": /shapes/0: faces before the file's first usemtl need the shape's \"material\"");
  EXPECT_EQ(load_error(dir, scene_json(R"("red": {"type": "diffuse"}, "white": {"type": "diffuse"})",
                                       R"(, "material": "white")")),
            s + ": /shapes/0/file: usemtl 'blue' names no material of the scene (defined: 'red', 'white')");
  // Without the key, usemtl is ignored: one shape with the shape's material.
  std::string plain = scene_json(three, R"(, "material": "white")");
  plain.replace(plain.find(R"("materials_by_name": true, )"), 27, "");
  EXPECT_EQ(load_scene_file(dir.write("s.json", plain))->shapes.size(), 1u);
  // Only OBJ files have usemtl.
  std::string inline_mesh = R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
    "materials": {"white": {"type": "diffuse"}},
    "shapes": [{"type": "mesh", "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "indices": [0, 1, 2],
                "material": "white", "materials_by_name": true}]})";
  EXPECT_EQ(load_error(dir, inline_mesh),
            s + ": /shapes/0/materials_by_name: needs an OBJ file (its usemtl names are matched to the scene's "
                "materials)");
}

}  // namespace
}  // namespace kozu
