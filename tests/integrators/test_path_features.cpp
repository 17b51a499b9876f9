// The first-hit features the denoiser and the AOVs take (PathIntegrator::li_features): through a perfect mirror
// they are those of what the mirror shows (albedo times the mirror's reflectance, that surface's normal), with
// the depth of the mirror itself; a rough metal keeps its own.
#include "support/render_test.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace kozu::test {
namespace {

PixelFeatures features_through(const std::string& sphere_material) {
  const auto scene = load_scene_text(fmt::format(R"({{
  "camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0], "resolution": [8, 8]}},
  "materials": {{"ball": {}, "red": {{"type": "diffuse", "albedo": [0.8, 0.1, 0.1]}}}},
  "shapes": [
    {{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "ball"}},
    {{"type": "quad", "material": "red", "vertices": [[-9, -9, 8], [-9, 9, 8], [9, 9, 8], [9, -9, 8]]}}
  ],
  "lights": [{{"type": "point", "position": [0, 3, 4], "intensity": 10}}]
}})",
                                                 sphere_material),
                                     "features.json", ".");
  const PathIntegrator integrator(*scene, 5);
  Sampler sampler(1);
  sampler.start(0, 0, 0);
  Arena arena;
  RayCounters counters;
  StopFlag stop(false);
  PixelFeatures f;
  integrator.li_features(Ray{Vec3(0, 0, 5), Vec3(0, 0, -1), kInfinity}, sampler, arena, counters, stop, f);
  return f;
}

TEST(PathFeatures, PassThroughAPerfectMirror) {
  const PixelFeatures f = features_through(R"({"type": "conductor", "metal": "Ag"})");
  ASSERT_TRUE(f.set);
  // Silver reflects ~95 % at normal incidence: the red wall's albedo, a little darker.
  EXPECT_GT(f.albedo.r, 0.6f);
  EXPECT_LE(f.albedo.r, 0.8f);
  EXPECT_LT(f.albedo.g, 0.1f);
  EXPECT_GT(f.albedo.g, 0.05f);
  EXPECT_NEAR(f.normal.z, -1.0f, 1e-4f);  // the wall, facing the reflected ray
  EXPECT_NEAR(f.depth, 4.0f, 1e-4f);      // the mirror's own depth
  EXPECT_NEAR(f.position.z, 1.0f, 1e-4f);
}

TEST(PathFeatures, StayOnARoughSurface) {
  for (const char* m :
       {R"({"type": "conductor", "metal": "Ag", "roughness": 0.4})", R"({"type": "diffuse", "albedo": 0.5})"}) {
    const PixelFeatures f = features_through(m);
    ASSERT_TRUE(f.set) << m;
    EXPECT_NEAR(f.normal.z, 1.0f, 1e-4f) << m;  // the sphere's own normal
    EXPECT_NEAR(f.depth, 4.0f, 1e-4f) << m;
  }
}

}  // namespace
}  // namespace kozu::test
