// "include" (docs/scene-format.md#include): a scene's files share one namespace of materials, media and objects,
// their shapes and lights add up, paths inside each file resolve against that file, and a cycle, a file included
// twice, a name or a camera defined twice, or a missing file is an error naming the files involved.
#include "core/error.h"
#include "scene/scene_loader.h"
#include "support/render_test.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

namespace kozu {
namespace {

using test::TempDir;

constexpr const char* kCamera = R"("camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "resolution": [8, 8]})";

std::string load_error(const std::filesystem::path& scene) {
  try {
    load_scene_file(scene);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(SceneInclude, MergesNamesShapesAndLightsWithPathsRelativeToEachFile) {
  TempDir dir;
  std::filesystem::create_directories(dir.path() / "lib" / "meshes");
  dir.write("lib/meshes/tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  // The included file names its mesh relative to itself, and uses a material the including file defines.
  dir.write("lib/props.json", R"({"comment": "props",
    "materials": {"red": {"type": "diffuse", "albedo": [0.8, 0.1, 0.1]}},
    "objects": {"tri": [{"type": "mesh", "file": "meshes/tri.obj", "material": "grey"}]},
    "shapes": [{"type": "mesh", "file": "meshes/tri.obj", "material": "grey"}],
    "lights": [{"type": "point", "position": [0, 3, 0], "intensity": 1}]})");
  const auto scene_file = dir.write("scene.json", std::string(R"({"include": ["lib/props.json"], )") + kCamera + R"(,
    "materials": {"grey": {"type": "diffuse"}},
    "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "red"},
               {"type": "instance", "object": "tri"}],
    "lights": [{"type": "environment", "radiance": 1}]})");
  const auto scene = load_scene_file(scene_file);
  ASSERT_EQ(scene->shapes.size(), 3u);  // the included file's shapes first
  EXPECT_EQ(scene->shapes[0]->material->name, "grey");
  EXPECT_EQ(scene->shapes[1]->material->name, "red");
  EXPECT_EQ(scene->lights.size(), 2u);
  // The included file and the mesh it names are the render's inputs (checkpoints hash them).
  const auto& in = scene->input_files;
  EXPECT_NE(std::find(in.begin(), in.end(), dir.path() / "lib/props.json"), in.end());
  EXPECT_NE(std::find(in.begin(), in.end(), dir.path() / "lib/meshes/tri.obj"), in.end());
}

TEST(SceneInclude, ErrorsNameTheFilesInvolved) {
  TempDir dir;
  const std::string d = dir.path().string() + "/";
  dir.write("a.json", R"({"include": ["b.json"]})");
  dir.write("b.json", R"({"include": ["a.json"]})");
  const auto cycle =
      dir.write("cycle.json", std::string(R"({"include": ["a.json"], )") + kCamera + R"(, "shapes": []})");
  EXPECT_EQ(load_error(cycle), d + "b.json: /include/0: " + d +
                                   "a.json includes itself through the chain of "
                                   "includes (a cycle)");

  dir.write("m1.json", R"({"materials": {"m": {"type": "diffuse"}}})");
  dir.write("m2.json", R"({"materials": {"m": {"type": "diffuse"}}})");
  const auto twice =
      dir.write("twice.json", std::string(R"({"include": ["m1.json", "m2.json"], )") + kCamera + R"(, "shapes": []})");
  EXPECT_EQ(load_error(twice),
            d + "m2.json: /materials/m: material 'm' is defined twice: in " + d + "m1.json and in " + d + "m2.json");

  const auto again =
      dir.write("again.json", std::string(R"({"include": ["m1.json", "m1.json"], )") + kCamera + R"(, "shapes": []})");
  EXPECT_EQ(load_error(again), d + "again.json: /include/1: " + d + "m1.json is included twice: by " + d +
                                   "again.json and by " + d + "again.json (its names would be defined twice)");

  dir.write("cam.json", std::string("{") + kCamera + "}");
  const auto cameras =
      dir.write("cameras.json", std::string(R"({"include": ["cam.json"], )") + kCamera + R"(, "shapes": []})");
  EXPECT_EQ(load_error(cameras), d + "cameras.json: /camera: 'camera' is given twice: in " + d + "cam.json and in " +
                                     d +
                                     "cameras.json (an included file and the file that includes it may not both "
                                     "set it)");
  // The camera may come from an included file alone.
  const auto borrowed = dir.write("borrowed.json", R"({"include": ["cam.json"], "shapes": [],
    "lights": [{"type": "environment", "radiance": 1}]})");
  EXPECT_EQ(load_error(borrowed), "");

  const auto missing =
      dir.write("missing.json", std::string(R"({"include": ["nope.json"], )") + kCamera + R"(, "shapes": []})");
  EXPECT_EQ(load_error(missing).rfind(d + "missing.json: /include/0: " + d + "nope.json: cannot open file", 0), 0u)
      << load_error(missing);
  const auto not_list =
      dir.write("notlist.json", std::string(R"({"include": "m1.json", )") + kCamera + R"(, "shapes": []})");
  EXPECT_EQ(load_error(not_list), d + "notlist.json: /include: expected an array of scene files");
  dir.write("unknown.json", R"({"materails": {}})");
  const auto typo =
      dir.write("typo.json", std::string(R"({"include": ["unknown.json"], )") + kCamera + R"(, "shapes": []})");
  EXPECT_EQ(load_error(typo).rfind(d + "unknown.json: /materails: unknown key", 0), 0u) << load_error(typo);
}

}  // namespace
}  // namespace kozu
