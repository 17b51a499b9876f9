// "camera_visible": false on shapes (Shape::camera_visible: camera rays pass through them) and on the environment
// (camera rays that escape see black), while both go on lighting the scene. What Blender's lights and transparent
// film need (docs/blender.md).
#include "support/render_test.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>

namespace kozu::test {
namespace {

// A diffuse wall (albedo 0.5) at z = -2 facing the camera at the origin, under a 128-gon light of radiance 1 and
// radius 3 at z = -1 that faces the wall, so the camera looks at the light's back first. Direct light only.
std::string scene(const char* camera_visible) {
  std::string poly;
  for (int i = 0; i < 128; ++i) {
    // Clockwise seen from the camera (+z), so the front side faces -z, towards the wall.
    const double a = -2.0 * M_PI * i / 128;
    poly += fmt::format("{}[{}, {}, -1]", i ? ", " : "", 3.0 * std::cos(a), 3.0 * std::sin(a));
  }
  return fmt::format(R"({{
    "camera": {{"position": [0, 0, 0], "look_at": [0, 0, -1], "fov": 2, "resolution": [8, 8]}},
    "render": {{"max_depth": 1, "filter": "box"}},
    "materials": {{"wall": {{"type": "diffuse", "albedo": 0.5}}}},
    "shapes": [{{"type": "quad", "material": "wall", "vertices": [[-50, -50, -2], [50, -50, -2], [50, 50, -2], [-50, 50, -2]]}},
               {{"type": "polygon", "emission": 1, "vertices": [{}]{}}}] }})",
                     poly, camera_visible);
}

// The form factor from the point (0, 0, -2), facing +z, to that polygon (Lambert's formula for a polygon).
double form_factor() {
  double sum = 0.0;
  for (int i = 0; i < 128; ++i) {
    const double a0 = -2.0 * M_PI * i / 128, a1 = -2.0 * M_PI * (i + 1) / 128;
    const Vec3d u0 = glm::normalize(Vec3d(3.0 * std::cos(a0), 3.0 * std::sin(a0), 1.0));
    const Vec3d u1 = glm::normalize(Vec3d(3.0 * std::cos(a1), 3.0 * std::sin(a1), 1.0));
    const Vec3d c = glm::cross(u0, u1);
    sum += std::acos(glm::dot(u0, u1)) * c.z / glm::length(c);
  }
  return std::abs(sum) / (2.0 * M_PI);
}

TEST(CameraVisible, HiddenLightStillLightsWhatTheCameraSeesThroughIt) {
  const TestRender t = render_json(scene(R"(, "camera_visible": false)"), 256);
  const ImageStats s = image_stats(t.film);
  // Radiance of the wall: albedo x L x F (the camera sees a spot 0.035 wide, where F changes by < 1e-4).
  const double expected = 0.5 * form_factor();
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(s.mean[c], expected, 5.0 * s.standard_error[c] + 2e-4) << "channel " << c;
}

TEST(CameraVisible, VisibleByDefault) {
  // The same scene without the key: the camera meets the light's back side, which neither emits nor reflects.
  const TestRender t = render_json(scene(""), 16);
  const ImageStats s = image_stats(t.film);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(s.mean[c], 0.0f);
}

TEST(CameraVisible, RejectsANonBoolean) {
  EXPECT_THROW(render_json(scene(R"(, "camera_visible": 0)"), 1), std::exception);
}

// A diffuse sphere (albedo 0.5) under a uniform environment of radiance 1, seen from `look` (the sphere fills a
// 5-degree view from +z; the view from -z looks away from it).
std::string environment_scene(const char* look_at, const char* camera_visible) {
  return fmt::format(R"({{
    "camera": {{"position": [0, 0, 4], "look_at": {}, "fov": 5, "resolution": [8, 8]}},
    "render": {{"max_depth": 1}},
    "materials": {{"m": {{"type": "diffuse", "albedo": 0.5}}}},
    "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}}],
    "lights": [{{"type": "environment", "radiance": 1{}}}] }})",
                     look_at, camera_visible);
}

TEST(CameraVisible, HiddenEnvironmentIsBlackToTheCamera) {
  const ImageStats hidden = image_stats(render_json(environment_scene("[0, 0, 8]", R"(, "camera_visible": false)"), 4).film);
  const ImageStats shown = image_stats(render_json(environment_scene("[0, 0, 8]", ""), 4).film);
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(hidden.mean[c], 0.0f);
    EXPECT_FLOAT_EQ(shown.mean[c], 1.0f);
  }
}

TEST(CameraVisible, HiddenEnvironmentStillLights) {
  // A convex diffuse surface under a uniform sky: radiance albedo x L wherever the camera sees it.
  const TestRender t = render_json(environment_scene("[0, 0, 0]", R"(, "camera_visible": false)"), 256);
  const ImageStats s = image_stats(t.film);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.mean[c], 0.5, 5.0 * s.standard_error[c] + 1e-4) << "channel " << c;
}

}  // namespace
}  // namespace kozu::test
