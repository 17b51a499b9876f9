// The error for an unknown shape type lists every type a scene may use, including the two the scene loader reads
// itself ("gltf", "instance"), and every type it lists is one the loader accepts.
#include "scene/scene_loader.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <regex>
#include <stdexcept>
#include <string>
#include <vector>

namespace kozu::test {
namespace {

std::string load_error(const std::string& shape) {
  const std::string json =
      fmt::format(R"({{"camera": {{"position": [0, 1, 5], "look_at": [0, 0, 0], "resolution": [8, 8]}},
 "materials": {{"m": {{"type": "diffuse", "albedo": 0.5}}}}, "shapes": [{}]}})",
                  shape);
  try {
    load_scene_text(json, "scene.json", ".");
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(ShapeTypes, UnknownTypeListsEveryType) {
  const std::string m = load_error(R"({"type": "cube", "material": "m"})");
  EXPECT_EQ(m,
            "scene.json: /shapes/0/type: unknown value 'cube' (expected one of 'sphere', 'quad', 'polygon', 'mesh', "
            "'gltf', 'instance')");
}

TEST(ShapeTypes, EveryListedTypeIsAccepted) {
  const std::string m = load_error(R"({"type": "cube", "material": "m"})");
  const std::string list = m.substr(m.find("expected one of"));
  std::vector<std::string> types;
  const std::regex quoted("'([a-z_]+)'");
  for (auto it = std::sregex_iterator(list.begin(), list.end(), quoted); it != std::sregex_iterator(); ++it)
    types.push_back((*it)[1]);
  ASSERT_GE(types.size(), 6u) << m;
  for (const std::string& type : types) {
    // Only the type is right: the loader complains about the missing keys, never about the type itself.
    const std::string e = load_error(fmt::format(R"({{"type": "{}", "material": "m"}})", type));
    EXPECT_NE(e, "") << type;
    EXPECT_EQ(e.find("unknown value"), std::string::npos) << type << ": " << e;
    EXPECT_EQ(e.find("read by the scene loader"), std::string::npos) << type << ": " << e;
  }
}

}  // namespace
}  // namespace kozu::test
