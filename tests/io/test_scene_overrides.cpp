// -D PATH=VALUE (scene/scene_overrides.h): parsing the argument, setting values in a parsed scene, the refusals,
// and a loaded scene that reads the overridden values with the file's own validation.
#include "core/error.h"
#include "scene/scene_loader.h"
#include "scene/scene_overrides.h"

#include <gtest/gtest.h>

namespace kozu {
namespace {

Json scene_json() {
  return Json::parse(R"({"camera": {"position": [0, 1, 5], "look_at": [0, 0, 0], "fov": 40, "resolution": [8, 8]},
    "materials": {"m": {"type": "diffuse", "albedo": 0.5}},
    "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}]})");
}

std::string error_of(const std::vector<std::string>& args) {
  Json root = scene_json();
  std::vector<SceneOverride> o;
  try {
    for (const auto& a : args) o.push_back(parse_scene_override(a));
    apply_scene_overrides(root, o, "s.json");
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(SceneOverrides, ValuesAreJsonOrElseStrings) {
  EXPECT_EQ(parse_scene_override("/camera/fov=30").value, Json(30));
  EXPECT_EQ(parse_scene_override("/a=[1, 2.5, 3]").value, Json::parse("[1, 2.5, 3]"));
  EXPECT_EQ(parse_scene_override("/a=true").value, Json(true));
  EXPECT_EQ(parse_scene_override("/a=conductor").value, Json("conductor"));
  EXPECT_EQ(parse_scene_override("/a=\"30\"").value, Json("30"));
  EXPECT_EQ(parse_scene_override("/a=").value, Json(""));
  EXPECT_EQ(parse_scene_override("/a=b=c").value, Json("b=c"));  // the first '=' ends the path
  EXPECT_EQ(parse_scene_override("/a~1b=1").path, "/a~1b");
}

TEST(SceneOverrides, SetsNestedKeysArrayElementsAndAppends) {
  Json root = scene_json();
  apply_scene_overrides(root,
                        {parse_scene_override("/camera/fov=30"), parse_scene_override("/materials/m/albedo=[1,0,0]"),
                         parse_scene_override("/shapes/0/radius=2"), parse_scene_override("/camera/fov=31"),
                         parse_scene_override("/shapes/-={\"type\": \"sphere\"}")},
                        "s.json");
  EXPECT_EQ(root["camera"]["fov"], Json(31));  // in order: the last one wins
  EXPECT_EQ(root["materials"]["m"]["albedo"], Json::parse("[1, 0, 0]"));
  EXPECT_EQ(root["shapes"][0]["radius"], Json(2));
  ASSERT_EQ(root["shapes"].size(), 2u);
  EXPECT_EQ(root["shapes"][1]["type"], Json("sphere"));
  // null removes.
  apply_scene_overrides(root, {parse_scene_override("/camera/fov=null"), parse_scene_override("/shapes/0=null")},
                        "s.json");
  EXPECT_FALSE(root["camera"].contains("fov"));
  ASSERT_EQ(root["shapes"].size(), 1u);
  EXPECT_EQ(root["shapes"][0]["type"], Json("sphere"));
  EXPECT_FALSE(root["shapes"][0].contains("radius"));
}

TEST(SceneOverrides, RefusalsNameTheArgumentOrThePath) {
  EXPECT_EQ(error_of({"camera/fov=30"}),
            "-D 'camera/fov=30': expected PATH=VALUE with PATH a JSON path from the scene's root, e.g. -D "
            "/camera/fov=30");
  EXPECT_EQ(error_of({"/camera/fov"}).rfind("-D '/camera/fov': expected PATH=VALUE", 0), 0u);
  EXPECT_EQ(error_of({"/a~2=1"}).rfind("-D '/a~2=1': '/a~2' is not a JSON path", 0), 0u);
  EXPECT_EQ(error_of({"/camera/position=[0, 1"}).rfind("-D '/camera/position=[0, 1': the value is not valid JSON", 0),
            0u);
  EXPECT_EQ(error_of({"/cam/fov=3"}), "s.json: /cam: no such object or array in the scene");
  EXPECT_EQ(error_of({"/shapes/3/radius=3"}), "s.json: /shapes/3: no such object or array in the scene");
  EXPECT_EQ(error_of({"/shapes/1=3"}),
            "s.json: /shapes: an array of 1 elements has no element '1' (an index, or - to append)");
  EXPECT_EQ(error_of({"/shapes/01=3"}),
            "s.json: /shapes: an array of 1 elements has no element '01' (an index, or - to append)");
  EXPECT_EQ(error_of({"/camera/fov/x=3"}), "s.json: /camera/fov: is a number, not an object or array");
}

TEST(SceneOverrides, TheNoteNamesTheOverrideBehindAnError) {
  const std::vector<SceneOverride> o = {parse_scene_override("/materials/m/type=conductor"),
                                        parse_scene_override("/camera/fovv=3")};
  EXPECT_EQ(override_note(o, "/materials/m/albedo"), " (set by -D /materials/m/type=conductor)");
  EXPECT_EQ(override_note(o, "/camera/fovv"), " (set by -D /camera/fovv=3)");
  EXPECT_EQ(override_note(o, "/shapes/0/radius"), "");
  EXPECT_EQ(override_note(o, "/materials/mm"), "");  // a prefix of the name is not the object
  // Beside a "type" and another key of the same object: the type is named.
  const std::vector<SceneOverride> two = {parse_scene_override("/camera/type=panorama"),
                                          parse_scene_override("/camera/resolution=[8,4]")};
  EXPECT_EQ(override_note(two, "/camera/fov"), " (set by -D /camera/type=panorama)");
  EXPECT_EQ(override_note(two, "/camera/resolution/0"), " (set by -D /camera/resolution=[8,4])");
}

// Through the loader: the overridden value is read (and validated) like the file's own.
TEST(SceneOverrides, TheLoaderReadsAndValidatesThem) {
  SceneLoadOptions options;
  options.overrides = {parse_scene_override("/camera/resolution=[12, 6]")};
  const auto scene = load_scene_text(scene_json().dump(), "s.json", ".", options);
  EXPECT_EQ(scene->camera.resolution(), Vec2i(12, 6));
  options.overrides = {parse_scene_override("/camera/fov=200")};
  try {
    load_scene_text(scene_json().dump(), "s.json", ".", options);
    ADD_FAILURE() << "fov 200 accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.json_path(), "/camera/fov");
  }
}

}  // namespace
}  // namespace kozu
