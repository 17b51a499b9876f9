// The directional light (lights/directional.h): radiance and density of escaped rays inside and outside its
// cone, the delta case, its power, and the parse errors of its scene keys.
#include "core/error.h"
#include "core/frame.h"
#include "core/rng.h"
#include "lights/directional.h"
#include "scene/scene_loader.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace kozu::test {
namespace {

const Vec3 kDirection(0.3f, -1.0f, 0.45f);

// The direction at angle theta from the unit axis a, towards b's side.
Vec3 off_axis(const Vec3d& a, double theta) {
  Vec3d s, t;
  orthonormal_basis(a, s, t);
  return Vec3(a * std::cos(theta) + s * std::sin(theta));
}

class DirectionalEval : public ::testing::TestWithParam<float> {};

// An escaped ray inside the cone sees L = E / (pi sin^2 theta_max), one outside sees 0; pdf likewise.
TEST_P(DirectionalEval, InsideAndOutsideTheCone) {
  const float diameter = GetParam();
  const Rgb E(1000.0f, 500.0f, 250.0f);
  const DirectionalLight light(kDirection, E, diameter);
  const Vec3d axis = -glm::normalize(Vec3d(kDirection));
  const double theta_max = 0.5 * diameter * M_PI / 180.0;
  const double L = 1.0 / (M_PI * std::sin(theta_max) * std::sin(theta_max));
  const double pdf = 1.0 / (2.0 * M_PI * (1.0 - std::cos(theta_max)));
  const LightSampleContext ctx{Vec3(0.0f), Vec3(0.0f)};
  EXPECT_FALSE(light.is_delta());
  EXPECT_TRUE(light.is_infinite());
  // 1e-3 inside and outside the edge in angle: well beyond the float rounding of a direction (~1e-7 rad).
  for (const double theta : {0.0, 0.5 * theta_max, 0.999 * theta_max}) {
    const LightHit hit{off_axis(axis, theta)};
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(light.eval(hit)[c], E[c] * L, 1e-5 * E[c] * L) << theta;
    EXPECT_NEAR(light.pdf(ctx, hit), pdf, 1e-5 * pdf) << theta;
  }
  for (const double theta : {1.001 * theta_max, 2.0 * theta_max, 0.5 * M_PI + 0.01, M_PI}) {
    const LightHit hit{off_axis(axis, std::min(theta, M_PI))};
    EXPECT_EQ(light.eval(hit), Rgb(0.0f)) << theta;
    EXPECT_EQ(light.pdf(ctx, hit), 0.0f) << theta;
  }
}

// A sample's radiance and density are what eval and pdf give for its direction.
TEST_P(DirectionalEval, SampleAgreesWithEvalAndPdf) {
  const DirectionalLight light(kDirection, Rgb(3.0f), GetParam());
  const LightSampleContext ctx{Vec3(1.0f, 2.0f, 3.0f), Vec3(0.0f, 1.0f, 0.0f)};
  Pcg32 rng(5);
  for (int i = 0; i < 10000; ++i) {
    // Off the rim (u.x < 0.999), where the edge test could go either way by rounding.
    const Vec2 u(0.999f * rng.next_float(), rng.next_float());
    const LightSample ls = light.sample(ctx, u);
    ASSERT_TRUE(ls.valid());
    ASSERT_TRUE(ls.infinite);
    ASSERT_NEAR(glm::length(ls.wi), 1.0f, 1e-6f);
    const LightHit hit{ls.wi};
    ASSERT_EQ(ls.radiance, light.eval(hit)) << i;
    ASSERT_EQ(ls.pdf, light.pdf(ctx, hit)) << i;
  }
}

INSTANTIATE_TEST_SUITE_P(Diameters, DirectionalEval, ::testing::Values(0.53f, 5.0f, 40.0f, 180.0f),
                         [](const auto& p) { return fmt::format("d{}", static_cast<int>(p.param * 100)); });

// angular_diameter 0: a delta light along the axis that no ray meets.
TEST(Directional, ZeroDiameterIsADeltaLight) {
  const Rgb E(2.0f, 3.0f, 4.0f);
  const DirectionalLight light(kDirection, E, 0.0f);
  EXPECT_TRUE(light.is_delta());
  EXPECT_FALSE(light.is_infinite());
  const LightSampleContext ctx{Vec3(0.0f), Vec3(0.0f)};
  const LightSample ls = light.sample(ctx, Vec2(0.3f, 0.7f));
  EXPECT_TRUE(ls.infinite);
  EXPECT_EQ(ls.pdf, 1.0f);
  EXPECT_EQ(ls.radiance, E);
  const Vec3 axis = Vec3(-glm::normalize(Vec3d(kDirection)));
  EXPECT_NEAR(glm::length(ls.wi - axis), 0.0f, 1e-6f);
  EXPECT_EQ(light.eval(LightHit{axis}), Rgb(0.0f));
  EXPECT_EQ(light.pdf(ctx, LightHit{axis}), 0.0f);
}

// Power E pi R^2 through the scene's bounding disk, for the cone and the delta light alike.
TEST(Directional, PowerThroughTheSceneDisk) {
  for (const float diameter : {0.0f, 0.53f, 30.0f}) {
    DirectionalLight light(kDirection, Rgb(1.0f, 2.0f, 3.0f), diameter);
    light.preprocess(Vec3(0.0f), 4.0f);
    const Rgb p = light.power();
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(p[c], (c + 1) * M_PI * 16.0, 1e-5 * p[c]) << diameter;
  }
}

// A scene with one directional light; loading it is expected to fail with `message`.
std::string load_error(const std::string& light) {
  const std::string json = fmt::format(R"({{
  "camera": {{"position": [0, 1, 5], "look_at": [0, 0, 0], "resolution": [8, 8]}},
  "materials": {{"m": {{"type": "diffuse"}}}},
  "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}}],
  "lights": [{{"type": "point", "position": [0, 3, 0], "intensity": 1}}, {}]
}})",
                                       light);
  try {
    load_scene_text(json, "scene.json", ".");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(loaded)";
}

TEST(DirectionalParse, ErrorsNameTheJsonPath) {
  EXPECT_EQ(load_error(R"({"type": "directional", "direction": [0, 0, 0], "irradiance": 1})"),
            "scene.json: /lights/1/direction: expected a nonzero vector");
  EXPECT_EQ(load_error(R"({"type": "directional", "irradiance": 1})"),
            "scene.json: /lights/1: missing required key 'direction'");
  EXPECT_EQ(load_error(R"({"type": "directional", "direction": [0, -1], "irradiance": 1})"),
            "scene.json: /lights/1/direction: expected an array of 3 numbers, got an array of 2");
  EXPECT_EQ(load_error(R"({"type": "directional", "direction": [0, -1, 0], "irradiance": [1, -2, 3]})"),
            "scene.json: /lights/1/irradiance/1: expected a number >= 0, got -2");
  EXPECT_EQ(load_error(R"({"type": "directional", "direction": [0, -1, 0], "irradiance": 1, "angular_diameter": 181})"),
            "scene.json: /lights/1/angular_diameter: expected a number in [0, 180], got 181");
  EXPECT_EQ(load_error(R"({"type": "directional", "direction": [0, -1, 0], "irradiance": 1, "angular_diameter": -1})"),
            "scene.json: /lights/1/angular_diameter: expected a number in [0, 180], got -1");
  EXPECT_EQ(load_error(R"({"type": "directional", "direction": [0, -1, 0], "irradiance": 1, "angular_diametre": 1})"),
            "scene.json: /lights/1/angular_diametre: unknown key 'angular_diametre' (did you mean "
            "'angular_diameter'?)");
  EXPECT_EQ(
      load_error(R"({"type": "directional", "direction": [0, -1, 0], "irradiance": 1, "angular_diameter": 1e-14})"),
      "scene.json: /lights/1/angular_diameter: 1e-14 degrees is too small to sample (density 4.18e+31, beyond "
      "kozu's range of at most 1e+30); use 0 for a delta directional light");
  // The sun's cone multiplies E by 1 / (pi sin^2 theta_max) = 4.7e4.
  EXPECT_EQ(
      load_error(R"({"type": "directional", "direction": [0, -1, 0], "irradiance": 1e28})"),
      "scene.json: /lights/1/irradiance: over an angular diameter of 0.53 degrees this is a radiance of 1.49e+32, "
      "beyond kozu's range (at most 1e+30)");
  // E pi R^2 with the scene's radius sqrt(3) (half the diagonal of the unit sphere's bounding box).
  EXPECT_EQ(
      load_error(R"({"type": "directional", "direction": [0, -1, 0], "irradiance": 1e30, "angular_diameter": 0})"),
      "scene.json: /lights/1: the light's power (9.42e+30) is beyond kozu's range (at most 1e+30); lower its "
      "emission or its size");
}

TEST(DirectionalParse, DefaultsToTheSun) {
  auto scene = load_scene_text(R"({
  "camera": {"position": [0, 1, 5], "look_at": [0, 0, 0], "resolution": [8, 8]},
  "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "emission": 1}],
  "lights": [{"type": "directional", "direction": [1, -2, 0.5], "irradiance": [3, 2, 1]},
             {"type": "directional", "direction": [0, -1, 0], "irradiance": 1, "angular_diameter": 0}]
})",
                               "scene.json", ".");
  ASSERT_EQ(scene->lights.size(), 3u);
  const auto* sun = dynamic_cast<const DirectionalLight*>(scene->lights[1].get());
  ASSERT_NE(sun, nullptr);
  EXPECT_NEAR(sun->one_minus_cos_max(), 1.0 - std::cos(0.53 / 2 * M_PI / 180.0), 1e-3 * sun->one_minus_cos_max());
  const Vec3 expected_axis = Vec3(-glm::normalize(Vec3d(1.0, -2.0, 0.5)));
  EXPECT_NEAR(glm::length(sun->to_light() - expected_axis), 0.0f, 1e-6f);
  // Only the cone is met by escaping rays; the delta light is not.
  ASSERT_EQ(scene->infinite_lights().size(), 1u);
  EXPECT_EQ(scene->infinite_lights()[0], scene->lights[1].get());
  EXPECT_TRUE(scene->lights[2]->is_delta());
}

}  // namespace
}  // namespace kozu::test
