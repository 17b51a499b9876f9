// Lights given by "power" in watts (lights/light_power.h, docs/lights.md "Light power in watts"): each light built
// from a power reports that power and emits as the light with the equivalent intensity or radiance; the documented
// mappings from Blender (Cycles) and pbrt-v4 give the irradiance those engines' sources imply; bad input is refused
// with the JSON path.
#include "core/error.h"
#include "lights/light.h"
#include "scene/scene_loader.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace kozu::test {
namespace {

// A scene with the given shapes (beside a small diffuse sphere) and lights.
std::unique_ptr<Scene> load(const std::string& shapes, const std::string& lights) {
  const std::string json = fmt::format(R"({{
  "camera": {{"position": [0, 1, 5], "look_at": [0, 0, 0], "resolution": [8, 8]}},
  "materials": {{"m": {{"type": "diffuse"}}}},
  "shapes": [{{"type": "sphere", "center": [0, -50, 0], "radius": 0.5, "material": "m"}}{}],
  "lights": [{}]
}})",
                                       shapes.empty() ? "" : ", " + shapes, lights);
  return load_scene_text(json, "scene.json", ".");
}

std::string load_error(const std::string& shapes, const std::string& lights) {
  try {
    load(shapes, lights);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(loaded)";
}

// Relative closeness of colours: float rounding of a handful of operations (1e-6 would fail for a wrong factor of
// any kind; the factors checked here are pi, 2, 4 and cosines).
void expect_rgb_near(const Rgb& a, const Rgb& b, const std::string& what) {
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 2e-6 * std::abs(b[c])) << what << " channel " << c;
}

// The incident radiance (irradiance per unit cosine for delta lights) a light's sample delivers at p.
Rgb received(const Light& light, const Vec3& p, const Vec3& n = Vec3(0.0f)) {
  const LightSample ls = light.sample({p, n}, Vec2(0.37f, 0.61f));
  EXPECT_TRUE(ls.valid());
  return ls.radiance;
}

// Points at angle theta (radians) off the -y axis, at distance d from the origin.
Vec3 below(double theta, double d) { return Vec3(float(d * std::sin(theta)), float(-d * std::cos(theta)), 0.0f); }

// smoothstep(a, b, x) as pbrt-v4 and kozu's spot define it.
double smoothstep(double a, double b, double x) {
  if (x <= a) return 0.0;
  if (x >= b) return 1.0;
  const double t = (x - a) / (b - a);
  return t * t * (3.0 - 2.0 * t);
}

const Rgb kPower(120.0f, 60.0f, 15.0f);
const std::string kPowerJson = "[120, 60, 15]";

TEST(LightPower, PointReportsItsPowerAndEmitsAsTheEquivalentIntensity) {
  const auto scene = load("", fmt::format(R"({{"type": "point", "position": [0, 0, 0], "power": {}}},
      {{"type": "point", "position": [0, 0, 0], "intensity": [{}, {}, {}]}})",
                                          kPowerJson, 120.0 / (4 * M_PI), 60.0 / (4 * M_PI), 15.0 / (4 * M_PI)));
  expect_rgb_near(scene->lights[0]->power(), kPower, "power");
  for (const double theta : {0.0, 1.0, 2.5})
    expect_rgb_near(received(*scene->lights[0], below(theta, 2.0)), received(*scene->lights[1], below(theta, 2.0)),
                    "irradiance");
}

TEST(LightPower, SpotReportsItsPowerAndEmitsAsTheEquivalentIntensity) {
  const double cone = 40.0, falloff = 25.0;
  const double k = 2 * M_PI * (1 - 0.5 * (std::cos(falloff * M_PI / 180) + std::cos(cone * M_PI / 180)));
  const auto scene = load("", fmt::format(R"({{"type": "spot", "position": [0, 0, 0], "direction": [0, -1, 0],
        "cone_angle": {0}, "falloff_angle": {1}, "power": {2}}},
      {{"type": "spot", "position": [0, 0, 0], "direction": [0, -1, 0], "cone_angle": {0}, "falloff_angle": {1},
        "intensity": [{3}, {4}, {5}]}})",
                                          cone, falloff, kPowerJson, 120.0 / k, 60.0 / k, 15.0 / k));
  expect_rgb_near(scene->lights[0]->power(), kPower, "power");
  for (const double theta_deg : {0.0, 20.0, 30.0, 39.0})
    expect_rgb_near(received(*scene->lights[0], below(theta_deg * M_PI / 180, 3.0)),
                    received(*scene->lights[1], below(theta_deg * M_PI / 180, 3.0)), "irradiance");
}

// A quad of area 2 x 3 facing -y at y = 1, one- or two-sided, and a sphere of radius 0.5.
struct AreaCase {
  std::string shape;  // without the emission key
  double area;
  bool two_sided;
};

TEST(LightPower, AreaLightsReportTheirPowerAndEmitTheEquivalentRadiance) {
  const std::string quad = R"("type": "quad", "vertices": [[-1, 1, -1.5], [1, 1, -1.5], [1, 1, 1.5], [-1, 1, 1.5]])";
  const std::string sphere = R"("type": "sphere", "center": [0, 3, 0], "radius": 0.5)";
  for (const AreaCase& c : {AreaCase{quad, 6.0, false}, AreaCase{quad + R"(, "two_sided": true)", 6.0, true},
                            AreaCase{sphere, M_PI, false}}) {
    const double per_unit = M_PI * c.area * (c.two_sided ? 2 : 1);
    const auto scene = load(fmt::format(R"({{{0}, "power": {1}}}, {{{0}, "emission": [{2}, {3}, {4}]}})", c.shape,
                                        kPowerJson, 120.0 / per_unit, 60.0 / per_unit, 15.0 / per_unit),
                            "");
    ASSERT_EQ(scene->lights.size(), 2u) << c.shape;
    expect_rgb_near(scene->lights[0]->power(), kPower, c.shape);
    const Rgb L = received(*scene->lights[0], Vec3(0.2f, 0.0f, 0.1f));
    expect_rgb_near(L, Rgb(Vec3d(kPower) / per_unit), c.shape);
    expect_rgb_near(L, received(*scene->lights[1], Vec3(0.2f, 0.0f, 0.1f)), c.shape);
  }
}

TEST(LightPower, AMeshSharesItsPowerAmongItsTriangles) {
  // Two triangles of areas 0.5 and 2: each emits the same radiance, 10 W in all.
  const auto scene = load(R"({"type": "mesh", "positions": [[0, 1, 0], [1, 1, 0], [0, 1, 1], [3, 1, 0], [5, 1, 0],
                                [3, 1, 2]], "indices": [0, 2, 1, 3, 5, 4], "power": 10})",
                          "");
  ASSERT_EQ(scene->lights.size(), 2u);
  const double L = 10.0 / (M_PI * 2.5);
  EXPECT_NEAR(scene->lights[0]->power()[0], M_PI * 0.5 * L, 1e-5);
  EXPECT_NEAR(scene->lights[1]->power()[0], M_PI * 2.0 * L, 1e-5);
}

TEST(LightPower, ZeroPowerIsAllowed) {
  const auto scene = load(R"({"type": "sphere", "center": [0, 3, 0], "radius": 0.5, "material": "m", "power": 0})",
                          R"({"type": "point", "position": [0, 0, 0], "power": 0},
                             {"type": "spot", "position": [0, 0, 0], "direction": [0, -1, 0], "power": 0})");
  ASSERT_EQ(scene->lights.size(), 2u);  // the sphere emits nothing, so it is no light
  for (const auto& l : scene->lights) EXPECT_EQ(l->power(), Rgb(0.0f));
}

TEST(LightPower, ErrorsNameTheKeysAndTheJsonPath) {
  EXPECT_EQ(load_error("", R"({"type": "point", "position": [0, 0, 0], "power": 1, "intensity": 1})"),
            "scene.json: /lights/0/power: give either 'intensity' or 'power' (watts), not both");
  EXPECT_EQ(load_error("", R"({"type": "spot", "position": [0, 0, 0], "direction": [0, -1, 0], "power": 1,
                               "intensity": 1})"),
            "scene.json: /lights/0/power: give either 'intensity' or 'power' (watts), not both");
  EXPECT_EQ(load_error(R"({"type": "sphere", "center": [0, 3, 0], "radius": 1, "power": 1, "emission": 1})", ""),
            "scene.json: /shapes/1/power: give either 'emission' or 'power' (watts), not both");
  EXPECT_EQ(load_error(R"({"type": "quad", "vertices": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], "power": 1,
                           "emission": {"type": "checker"}})",
                       ""),
            "scene.json: /shapes/1/power: give either 'emission' or 'power' (watts), not both");
  EXPECT_EQ(load_error("", R"({"type": "point", "position": [0, 0, 0]})"),
            "scene.json: /lights/0: missing required key 'intensity' (or 'power' in watts)");
  EXPECT_EQ(load_error("", R"({"type": "point", "position": [0, 0, 0], "power": -5})"),
            "scene.json: /lights/0/power: expected a number in [0, 1e+30], got -5");
  EXPECT_EQ(load_error("", R"({"type": "spot", "position": [0, 0, 0], "direction": [0, -1, 0], "power": [1, -2, 3]})"),
            "scene.json: /lights/0/power/1: expected a number in [0, 1e+30], got -2");
  EXPECT_EQ(load_error(R"({"type": "sphere", "center": [0, 3, 0], "radius": 1, "power": -1})", ""),
            "scene.json: /shapes/1/power: expected a number in [0, 1e+30], got -1");
  EXPECT_EQ(load_error("", R"({"type": "point", "position": [0, 0, 0], "power": "nan"})"),
            "scene.json: /lights/0/power: expected [r, g, b] or a number, got the string \"nan\"");
  EXPECT_EQ(load_error("", R"({"type": "directional", "direction": [0, -1, 0], "power": 1})"),
            "scene.json: /lights/0/power: this light takes no 'power': a distant light's power depends on the "
            "scene's size (docs/lights.md \"Light power in watts\"); give 'irradiance'");
  EXPECT_EQ(load_error("", R"({"type": "environment", "radiance": 1, "power": 1})"),
            "scene.json: /lights/0/power: this light takes no 'power': an environment's power depends on the "
            "scene's size (docs/lights.md \"Light power in watts\"); give 'radiance' or 'file'");
  // 1 W from a sphere of radius 1e-20 (area 1.26e-39) is a radiance of 1 / (pi A) = 2.5e38.
  EXPECT_EQ(load_error(R"({"type": "sphere", "center": [0, 3, 0], "radius": 1e-20, "power": 1})", ""),
            "scene.json: /shapes/1/power: 1 W over an area of 1.26e-39 is a radiance of 2.53e+38, beyond kozu's "
            "range (at most 1e+30)");
  // A spot of 1e-3 degrees (no falloff) has 2 pi (1 - (1 + cos cone) / 2) = 4.8e-10 sr: 1e25 W is 2.1e34 W/sr.
  EXPECT_EQ(load_error("", R"({"type": "spot", "position": [0, 0, 0], "direction": [0, -1, 0], "cone_angle": 1e-3,
                               "falloff_angle": 0, "power": 1e25})"),
            "scene.json: /lights/0/power: 1e+25 W needs axial intensity (W/sr) = 2.09e+34, beyond kozu's range (at "
            "most 1e+30)");
}

// ---- Mappings from other renderers (docs/lights.md "From Blender and pbrt-v4") ----

const Rgb kColour(1.0f, 0.8f, 0.5f);
constexpr double kWatts = 50.0;

// Blender point light of P W and colour c: Cycles evaluates a point light as a disk of radius r whose radiance is
// c P / (4 pi) / (pi r^2) (eval_fac = 1 / (4 pi) x invarea, kernel/light/point.h), so the irradiance at distance d on a
// facing surface is c P / (4 pi d^2). In kozu: "power": c P.
TEST(LightPowerMapping, BlenderPoint) {
  const auto scene = load("", R"({"type": "point", "position": [0, 0, 0], "power": [50, 40, 25]})");
  for (const double d : {1.0, 3.0})
    expect_rgb_near(received(*scene->lights[0], below(0.3, d)), Rgb(Vec3d(kColour) * kWatts / (4 * M_PI * d * d)),
                    "Blender point");
}

// Blender spot of P W, colour c, spot_size S, blend b: the intensity on the axis is that of the point light of the same
// power, c P / (4 pi), whatever the cone; off the axis Cycles multiplies by
// smoothstep((cos theta - cos(S/2)) / ((1 - cos(S/2)) b)) (kernel/light/spot.h, scene/light.cpp). In kozu:
// "intensity": c P / (4 pi), cone_angle S/2, falloff_angle acos(cos(S/2) + b (1 - cos(S/2))).
TEST(LightPowerMapping, BlenderSpot) {
  const double S = 70.0 * M_PI / 180, b = 0.3;
  const double cos_half = std::cos(S / 2), falloff = std::acos(cos_half + b * (1 - cos_half));
  const auto scene =
      load("", fmt::format(R"({{"type": "spot", "position": [0, 0, 0], "direction": [0, -1, 0],
      "intensity": [{}, {}, {}], "cone_angle": {}, "falloff_angle": {}}})",
                           50 / (4 * M_PI), 40 / (4 * M_PI), 25 / (4 * M_PI), 35.0, falloff * 180 / M_PI));
  for (const double theta_deg : {0.0, 20.0, 29.0, 32.0, 34.5, 36.0}) {
    const double theta = theta_deg * M_PI / 180, d = 2.0;
    const double x = (std::cos(theta) - cos_half) / ((1 - cos_half) * b);
    const double cycles = smoothstep(0.0, 1.0, x);  // Cycles' smoothstepf(x)
    const Rgb expected(Vec3d(kColour) * kWatts / (4 * M_PI * d * d) * cycles);
    const Rgb got = received(*scene->lights[0], below(theta, d));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], expected[c], 2e-5 * kWatts / (4 * M_PI * d * d)) << theta_deg;
  }
}

// Blender area light of P W, colour c and area A (Normalize on): Cycles gives it radiance c P / (4 A) on its front
// (eval_fac = 0.25 x invarea with invarea = 1 / A, kernel/light/area.h), so it emits pi/4 x c P. In kozu: a one-sided
// quad with "emission": c P / (4 A), i.e. "power": pi/4 x c P.
TEST(LightPowerMapping, BlenderArea) {
  const double A = 2.0 * 3.0;
  const auto scene = load(fmt::format(R"({{"type": "quad", "vertices": [[-1, 1, -1.5], [1, 1, -1.5], [1, 1, 1.5],
      [-1, 1, 1.5]], "power": [{}, {}, {}]}})",
                                      M_PI / 4 * 50, M_PI / 4 * 40, M_PI / 4 * 25),
                          "");
  expect_rgb_near(received(*scene->lights[0], Vec3(0.1f, 0.0f, 0.2f)), Rgb(Vec3d(kColour) * kWatts / (4 * A)),
                  "Blender area");
}

// Blender sun of strength S (W/m^2, the irradiance on a surface facing it) and colour c: "irradiance": c S.
TEST(LightPowerMapping, BlenderSun) {
  const auto scene = load("", R"({"type": "directional", "direction": [0, -1, 0], "irradiance": [5, 4, 2.5],
                                  "angular_diameter": 0})");
  expect_rgb_near(received(*scene->lights[0], Vec3(0.0f)), Rgb(Vec3d(kColour) * 5.0), "Blender sun");
}

// pbrt-v4 point light, "rgb I" c and "power" P: scale = P / (4 pi) / SpectrumToPhotometric(I), and for an RGB
// illuminant SpectrumToPhotometric is that of the colour space's illuminant alone (util/spectrum.cpp), which makes
// I = c render as the RGB value c: the intensity is c P / (4 pi) (lights.cpp, PointLight::Create). In kozu:
// "power": c P.
TEST(LightPowerMapping, PbrtPoint) {
  const auto scene = load("", R"({"type": "point", "position": [0, 0, 0], "power": [50, 40, 25]})");
  const double d = 2.5;
  expect_rgb_near(received(*scene->lights[0], below(1.2, d)), Rgb(Vec3d(kColour) * kWatts / (4 * M_PI * d * d)),
                  "pbrt point");
}

// pbrt-v4 spot, "coneangle" a, "conedeltaangle" delta, "power" P, "rgb I" c: scale = P / k_e with
// k_e = 2 pi ((1 - cos(a - delta)) + (cos(a - delta) - cos a) / 2) and I(theta) = c scale
// smoothstep(cos a, cos(a - delta), cos theta) (SpotLight::Create, SpotLight::I). In kozu: "power": c P,
// cone_angle a, falloff_angle a - delta.
TEST(LightPowerMapping, PbrtSpot) {
  const double a = 30.0 * M_PI / 180, delta = 10.0 * M_PI / 180;
  const auto scene = load("", R"({"type": "spot", "position": [0, 0, 0], "direction": [0, -1, 0], "cone_angle": 30,
                                  "falloff_angle": 20, "power": [50, 40, 25]})");
  const double k_e = 2 * M_PI * ((1 - std::cos(a - delta)) + (std::cos(a - delta) - std::cos(a)) / 2);
  for (const double theta_deg : {0.0, 15.0, 22.0, 27.0, 31.0}) {
    const double theta = theta_deg * M_PI / 180, d = 2.0;
    const double I = kWatts / k_e * smoothstep(std::cos(a), std::cos(a - delta), std::cos(theta));
    const Rgb expected(Vec3d(kColour) * I / (d * d));
    const Rgb got = received(*scene->lights[0], below(theta, d));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], expected[c], 2e-5 * kWatts / k_e / (d * d)) << theta_deg;
  }
}

// pbrt-v4 "diffuse" area light, "power" P, "rgb L" c, "twosided": scale = P / (pi A (2 if two-sided))
// (DiffuseAreaLight::Create). In kozu: the shape's "power": c P with the same two_sided.
TEST(LightPowerMapping, PbrtDiffuseArea) {
  for (const bool two_sided : {false, true}) {
    const auto scene = load(fmt::format(R"({{"type": "quad", "vertices": [[-1, 1, -1.5], [1, 1, -1.5], [1, 1, 1.5],
        [-1, 1, 1.5]], "two_sided": {}, "power": [50, 40, 25]}})",
                                        two_sided),
                            "");
    const double k_e = (two_sided ? 2 : 1) * 6.0 * M_PI;
    expect_rgb_near(received(*scene->lights[0], Vec3(0.1f, 0.0f, 0.2f)), Rgb(Vec3d(kColour) * kWatts / k_e),
                    two_sided ? "two-sided" : "one-sided");
  }
}

}  // namespace
}  // namespace kozu::test
