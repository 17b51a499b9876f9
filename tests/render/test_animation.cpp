// The keyframed camera (scene/animation.h): it passes through every key, its path and speed are continuous across
// keys (first derivatives from both sides agree, the Catmull–Rom property a linear blend lacks), and it holds still
// outside the keys' times.
#include "scene/animation.h"

#include <gtest/gtest.h>

namespace kozu {
namespace {

Animation three_keys() {
  Animation a;
  a.fps = 24;
  a.frames = 48;
  a.camera = {{0.0, Vec3(0, 1, 5), Vec3(0), 40.0f},
              {0.5, Vec3(3, 1, 3), Vec3(0, 0.5f, 0), 30.0f},
              {2.0, Vec3(4, 2, -2), Vec3(1, 0, 0), 50.0f}};
  return a;
}

TEST(Animation, PassesThroughTheKeys) {
  const Animation a = three_keys();
  for (const CameraKey& k : a.camera) {
    const CameraKey c = a.camera_at(k.time, {});
    EXPECT_NEAR(glm::length(c.position - k.position), 0.0f, 1e-5f) << k.time;
    EXPECT_NEAR(glm::length(c.look_at - k.look_at), 0.0f, 1e-5f) << k.time;
    EXPECT_NEAR(c.fov, k.fov, 1e-4f) << k.time;
  }
}

TEST(Animation, VelocityIsContinuousAtAnInteriorKey) {
  const Animation a = three_keys();
  constexpr double h = 1e-3;
  const double t = 0.5;
  const Vec3 left = (a.camera_at(t, {}).position - a.camera_at(t - h, {}).position) / float(h);
  const Vec3 right = (a.camera_at(t + h, {}).position - a.camera_at(t, {}).position) / float(h);
  // Non-uniform Catmull–Rom tangent at the key: (p2 - p0) / (t2 - t0).
  const Vec3 expected = (a.camera[2].position - a.camera[0].position) / 2.0f;
  EXPECT_LT(glm::length(left - expected), 0.02f);
  EXPECT_LT(glm::length(right - expected), 0.02f);
  // A linear blend would jump from (p1 - p0) / 0.5 to (p2 - p1) / 1.5 here.
  EXPECT_GT(glm::length((a.camera[1].position - a.camera[0].position) / 0.5f - expected), 1.0f);
}

TEST(Animation, HoldsStillOutsideTheKeys) {
  const Animation a = three_keys();
  EXPECT_EQ(a.camera_at(-1.0, {}).position, a.camera.front().position);
  EXPECT_EQ(a.camera_at(10.0, {}).position, a.camera.back().position);
  CameraKey still;
  still.position = Vec3(7, 8, 9);
  EXPECT_EQ(Animation{}.camera_at(0.3, still).position, still.position);
}

}  // namespace
}  // namespace kozu
