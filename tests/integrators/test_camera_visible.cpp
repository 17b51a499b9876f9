// Shapes with "camera_visible": false (Shape::camera_visible): camera rays pass through them, while they go on
// lighting the scene. What Blender's lights need (Cycles hides them from the camera; docs/blender.md).
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

}  // namespace
}  // namespace kozu::test
