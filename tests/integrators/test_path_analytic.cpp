// Scene-level checks of the path tracer against closed forms.
//
// Tolerances: each comparison allows z = 5 standard errors of the rendered mean (estimated from
// the film's per-pixel variances) plus an explicit bias budget where the camera footprint makes
// the rendered quantity differ from the closed form (stated per test). For zero-variance
// estimators the budget is float round-off only.
#include "support/render_test.h"

#include "io/image_io.h"
#include "lights/environment.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace kozu::test {
namespace {

constexpr double kZ = 5.0;

void expect_near_rgb(const ImageStats& s, const Rgb& expected, double bias_budget, const std::string& what) {
  for (int c = 0; c < 3; ++c) {
    const double tol = kZ * s.standard_error[c] + bias_budget * std::abs(expected[c]) + 1e-5 * std::abs(expected[c]);
    EXPECT_NEAR(s.mean[c], expected[c], tol)
        << what << " channel " << c << " (standard error " << s.standard_error[c] << ")";
  }
}

// A sphere of the given material in a uniform environment of radiance 1, seen from outside.
std::string furnace_scene(const std::string& material, int max_depth) {
  return fmt::format(R"({{
    "camera": {{"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 35, "resolution": [32, 32]}},
    "render": {{"max_depth": {}}},
    "materials": {{"m": {}}},
    "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}}],
    "lights": [{{"type": "environment", "radiance": 1}}] }})",
                     max_depth, material);
}

struct FurnaceCase {
  const char* name;
  const char* material;
};

class WhiteFurnace : public ::testing::TestWithParam<FurnaceCase> {};

// Energy-conserving, non-absorbing surfaces in a uniform unit environment render 1 everywhere.
TEST_P(WhiteFurnace, RendersOneEverywhere) {
  const auto& c = GetParam();
  const TestRender t = render_json(furnace_scene(c.material, 64), 64);
  const ImageStats s = image_stats(t.film);
  expect_near_rgb(s, Rgb(1.0f), 0.0, c.name);
  // Every pixel, not just the mean: 5 standard errors of that pixel (plus round-off).
  int bad = 0;
  for (int y = 0; y < t.film.height(); ++y)
    for (int x = 0; x < t.film.width(); ++x) {
      const Rgb m = t.film.mean(x, y), v = t.film.variance_of_mean(x, y);
      for (int ch = 0; ch < 3; ++ch)
        if (std::abs(m[ch] - 1.0) > kZ * std::sqrt(v[ch]) + 1e-4) ++bad;
    }
  EXPECT_EQ(bad, 0) << c.name;
  EXPECT_EQ(t.result.film.discarded_samples, 0u);
}

INSTANTIATE_TEST_SUITE_P(Materials, WhiteFurnace,
                         ::testing::Values(FurnaceCase{"diffuse", R"({"type": "diffuse", "albedo": 1})"},
                                           FurnaceCase{"mirror", R"({"type": "conductor"})"},
                                           FurnaceCase{"glass_1_5", R"({"type": "dielectric", "ior": 1.5})"},
                                           FurnaceCase{"glass_1_33", R"({"type": "dielectric", "ior": 1.33})"},
                                           FurnaceCase{"glass_0_7", R"({"type": "dielectric", "ior": 0.7})"}),
                         [](const auto& p) { return std::string(p.param.name); });

// Big analytic spheres: a ground sphere whose top is at the origin (centre (0, -R, 0)), seen from just above,
// under a uniform sky. Hit points there have small coordinates but the intersection's error grows with R and
// |centre|; rays that left within that error re-hit the sphere, and a diffuse ground of albedo 0.5 showed rings
// down to 0.023 at R = 1000. With the error bound (Sphere::position_error) the diffuse ground is exactly
// 0.5 (a convex surface sees the whole sky), and an albedo-1 ground and a glass ground vanish in the furnace.
TEST(PathIntegrator, BigGroundSpheresDoNotSelfIntersect) {
  for (double R : {1e3, 1e4, 1e5}) {
    for (const auto& [material, expected] :
         {std::pair{R"({"type": "diffuse", "albedo": 0.5})", 0.5}, std::pair{R"({"type": "diffuse", "albedo": 1})", 1.0},
          std::pair{R"({"type": "dielectric", "ior": 1.5})", 1.0}}) {
      const std::string json = fmt::format(R"({{
        "camera": {{"position": [0, 2, 3], "look_at": [0, 0, 0], "fov": 30, "resolution": [24, 16]}},
        "render": {{"max_depth": 64}},
        "materials": {{"m": {}}},
        "shapes": [{{"type": "sphere", "center": [0, {}, 0], "radius": {}, "material": "m"}}],
        "lights": [{{"type": "environment", "radiance": 1}}] }})",
                                           material, -R, R);
      const TestRender t = render_json(json, 32);
      // The view's top edge is 18.7° below the horizontal and the horizon dips at most 3.6° (R = 1000, eye
      // height 2): every pixel sees the ground, and is within 5 of its own standard errors of the value.
      int bad = 0;
      double worst = 1.0;
      for (int y = 0; y < t.film.height(); ++y)
        for (int x = 0; x < t.film.width(); ++x) {
          const Rgb m = t.film.mean(x, y), v = t.film.variance_of_mean(x, y);
          if (std::abs(m.g - expected) > kZ * std::sqrt(v.g) + 1e-4) ++bad;
          worst = std::min(worst, double(m.g));
        }
      EXPECT_EQ(bad, 0) << "radius " << R << ", " << material << ", darkest pixel " << worst;
    }
  }
}

// An emitting, reflecting enclosure seen from inside: L = Le / (1 - a) (geometric series of bounces).
TEST(PathIntegrator, EnclosureConvergesToGeometricSeries) {
  for (float albedo : {0.5f, 0.8f}) {
    const std::string json = fmt::format(R"({{
      "camera": {{"position": [0, 0, 0.3], "look_at": [0, 0, -1], "fov": 90, "resolution": [24, 24]}},
      "render": {{"max_depth": 1000}},
      "materials": {{"m": {{"type": "diffuse", "albedo": {}}}}},
      "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m",
                   "emission": 0.5, "two_sided": true}}] }})",
                                         albedo);
    const TestRender t = render_json(json, 256);
    // Russian roulette is unbiased; max_depth 1000 truncates a^1000 of the series (negligible).
    expect_near_rgb(image_stats(t.film), Rgb(0.5f / (1.0f - albedo)), 0.0, fmt::format("albedo {}", albedo));
  }
}

// A diffuse quad of albedo rho under a uniform sky of radiance L renders rho * L.
TEST(PathIntegrator, DiffuseQuadUnderUniformSky) {
  const Rgb rho(0.25f, 0.5f, 0.9f), L(2.0f, 1.0f, 0.5f);
  const std::string json = fmt::format(R"({{
    "camera": {{"position": [0, 3, 0.5], "look_at": [0, 0, 0], "fov": 30, "resolution": [16, 16]}},
    "materials": {{"m": {{"type": "diffuse", "albedo": [{}, {}, {}]}}}},
    "shapes": [{{"type": "quad", "material": "m", "vertices": [[-5, 0, 5], [5, 0, 5], [5, 0, -5], [-5, 0, -5]]}}],
    "lights": [{{"type": "environment", "radiance": [{}, {}, {}]}}] }})",
                                       rho.r, rho.g, rho.b, L.r, L.g, L.b);
  const TestRender t = render_json(json, 16);
  expect_near_rgb(image_stats(t.film), rho * L, 0.0, "rho * L");
}

// Radiance of a Lambertian point straight below a centred square light (half-size a, height h):
// rho * F, with F the point-to-rectangle form factor (4 corner terms).
double square_form_factor(double a, double h) {
  const double x = a / h;
  const double corner = (x / std::sqrt(1 + x * x)) * std::atan(x / std::sqrt(1 + x * x));
  return 4.0 * 2.0 * corner / (2.0 * M_PI);
}

// Camera footprint: a 0.5 degree field of view at distance 1 spans +-0.0044 around the centre,
// where the form factor changes by less than 1e-4 relative (second order in the offset).
constexpr double kFootprintBudget = 2e-4;

TEST(PathIntegrator, SquareAreaLightFormFactor) {
  for (int depth : {1, 4}) {
    const std::string json = fmt::format(R"({{
      "camera": {{"position": [0, 1, 0.0001], "look_at": [0, 0, 0], "fov": 0.5, "resolution": [4, 4]}},
      "render": {{"max_depth": {}}},
      "materials": {{"m": {{"type": "diffuse", "albedo": 0.8}}}},
      "shapes": [{{"type": "quad", "material": "m", "vertices": [[-20, 0, 20], [20, 0, 20], [20, 0, -20], [-20, 0, -20]]}},
                 {{"type": "quad", "emission": 3, "vertices": [[-1, 1.5, -1], [1, 1.5, -1], [1, 1.5, 1], [-1, 1.5, 1]]}}] }})",
                                         depth);
    const TestRender t = render_json(json, 4096);
    // Only the floor reflects (the light has no material), so every depth gives the direct term.
    expect_near_rgb(image_stats(t.film), Rgb(static_cast<float>(0.8 * 3.0 * square_form_factor(1.0, 1.5))),
                    kFootprintBudget, fmt::format("max_depth {}", depth));
  }
}

// A wide square light (half-size 4) low above the floor (height 0.5) and a clear (density 0) medium slab between them
// whose top face lies 0.05 below the light, the camera inside it: most shadow rays leave the slab at grazing angles
// and must still reach the light. (A shadow ray shortened by the distance to each boundary's offset origin overshot
// its end at grazing angles and hit the light behind it: this read 0.92 of the closed form.)
TEST(PathIntegrator, SquareAreaLightThroughMediumBoundaries) {
  const std::string json = R"({
    "camera": {"position": [0, 0.3, 0.0001], "look_at": [0, 0, 0], "fov": 0.5, "resolution": [4, 4], "medium": "clear"},
    "render": {"max_depth": 1},
    "materials": {"m": {"type": "diffuse", "albedo": 0.8}},
    "media": {"clear": {"type": "homogeneous", "density": 0}},
    "shapes": [{"type": "quad", "material": "m", "vertices": [[-20, 0, 20], [20, 0, 20], [20, 0, -20], [-20, 0, -20]]},
               {"type": "mesh", "interior": "clear",
                "positions": [[-9, 0.05, -9], [-9, 0.05, 9], [-9, 0.45, -9], [-9, 0.45, 9], [9, 0.05, -9], [9, 0.05, 9],
                              [9, 0.45, -9], [9, 0.45, 9]],
                "indices": [0, 1, 3, 0, 3, 2, 4, 6, 7, 4, 7, 5, 0, 4, 5, 0, 5, 1, 2, 3, 7, 2, 7, 6, 0, 2, 6, 0, 6, 4,
                            1, 5, 7, 1, 7, 3]},
               {"type": "quad", "emission": 3, "vertices": [[-4, 0.5, -4], [4, 0.5, -4], [4, 0.5, 4], [-4, 0.5, 4]]}] })";
  const TestRender t = render_json(json, 4096);
  // The camera's footprint at distance 0.3 is a third of SquareAreaLightFormFactor's: its budget holds.
  expect_near_rgb(image_stats(t.film), Rgb(static_cast<float>(0.8 * 3.0 * square_form_factor(4.0, 0.5))),
                  kFootprintBudget, "through the slab");
}

// A spherical emitter of radius R at distance d above a Lambertian point: rho * L * (R / d)^2.
TEST(PathIntegrator, SphereLightIrradiance) {
  const std::string json = R"({
    "camera": {"position": [0, 0.5, 0.0001], "look_at": [0, 0, 0], "fov": 0.5, "resolution": [4, 4]},
    "render": {"max_depth": 1},
    "materials": {"m": {"type": "diffuse", "albedo": 0.5}},
    "shapes": [{"type": "quad", "material": "m", "vertices": [[-20, 0, 20], [20, 0, 20], [20, 0, -20], [-20, 0, -20]]},
               {"type": "sphere", "center": [0.6, 2, 0], "radius": 0.4, "emission": 5}] })";
  const TestRender t = render_json(json, 4096);
  // Off-axis sphere: E = pi L (R/d)^2 cos(theta), d = |c - p|, cos(theta) = c.y / d.
  const double d2 = 0.6 * 0.6 + 2.0 * 2.0, cos_t = 2.0 / std::sqrt(d2);
  expect_near_rgb(image_stats(t.film), Rgb(static_cast<float>(0.5 * 5.0 * (0.4 * 0.4 / d2) * cos_t)), 1e-3,
                  "sphere light");
}

// Point and spot lights: rho / pi * I cos(theta) / r^2.
TEST(PathIntegrator, PointAndSpotLights) {
  for (const char* light :
       {R"({"type": "point", "position": [0, 2, 0], "intensity": 4})",
        R"({"type": "spot", "position": [0, 2, 0], "look_at": [0, 0, 0], "intensity": 4, "cone_angle": 20})"}) {
    const std::string json = fmt::format(R"({{
      "camera": {{"position": [0, 1, 0.0001], "look_at": [0, 0, 0], "fov": 0.5, "resolution": [4, 4]}},
      "render": {{"max_depth": 1}},
      "materials": {{"m": {{"type": "diffuse", "albedo": 0.6}}}},
      "shapes": [{{"type": "quad", "material": "m", "vertices": [[-20, 0, 20], [20, 0, 20], [20, 0, -20], [-20, 0, -20]]}}],
      "lights": [{}] }})",
                                         light);
    const TestRender t = render_json(json, 64);
    expect_near_rgb(image_stats(t.film), Rgb(static_cast<float>(0.6 / M_PI * 4.0 / 4.0)), kFootprintBudget, light);
  }
}

// A Lambertian plane under a directional light whose whole cone is above it: rho / pi * E cos(alpha). At 30
// degrees BSDF sampling meets the cone often, so a wrong MIS weight or a pdf that disagrees with the sampling
// would bias the sum; 0.53 is the sun, 0 the delta light. The plane is lit everywhere alike (no footprint bias).
TEST(PathIntegrator, DirectionalLightIrradiance) {
  const double alpha = 25.0 * M_PI / 180.0;  // from the zenith, towards -x; 25 + 120 / 2 < 90
  for (const float diameter : {0.0f, 0.53f, 120.0f}) {
    const std::string json = fmt::format(R"({{
      "camera": {{"position": [0, 1, 0.0001], "look_at": [0, 0, 0], "fov": 0.5, "resolution": [4, 4]}},
      "render": {{"max_depth": 1}},
      "materials": {{"m": {{"type": "diffuse", "albedo": 0.7}}}},
      "shapes": [{{"type": "quad", "material": "m", "vertices": [[-20, 0, 20], [20, 0, 20], [20, 0, -20], [-20, 0, -20]]}}],
      "lights": [{{"type": "directional", "direction": [{}, {}, 0], "irradiance": [3, 2, 1], "angular_diameter": {}}}] }})",
                                         std::sin(alpha), -std::cos(alpha), diameter);
    const TestRender t = render_json(json, 1024);
    expect_near_rgb(image_stats(t.film), Rgb(3.0f, 2.0f, 1.0f) * static_cast<float>(0.7 / M_PI * std::cos(alpha)), 0.0,
                    fmt::format("angular diameter {}", diameter));
  }
}

// Looking straight at the sun's disk, every pixel sees its radiance E / (pi sin^2 theta_max).
TEST(PathIntegrator, CameraSeesTheSunsRadiance) {
  const std::string json = R"({
    "camera": {"position": [0, 0, 0], "look_at": [1, 2, -2], "fov": 0.2, "resolution": [4, 4]},
    "shapes": [{"type": "sphere", "center": [0, -10, 0], "radius": 1, "material": "m"}],
    "materials": {"m": {"type": "diffuse"}},
    "lights": [{"type": "directional", "direction": [-1, -2, 2], "irradiance": 5}] })";
  const TestRender t = render_json(json, 4);
  const double s = std::sin(0.5 * 0.53 * M_PI / 180.0);
  // The 0.2 degree view lies inside the 0.53 degree disk; the estimator has no variance (float round-off only).
  expect_near_rgb(image_stats(t.film), Rgb(static_cast<float>(5.0 / (M_PI * s * s))), 0.0, "sun disk");
}

// An importance-sampled lat-long environment: the render of an upward-facing Lambertian point must
// equal rho / pi * integral of L(w) cos(theta) over the upper hemisphere, computed here by dense
// quadrature of the light's own radiance lookup.
TEST(PathIntegrator, EnvironmentMapMatchesQuadrature) {
  TempDir dir;
  // A 64x32 map: dim sky gradient plus a small very bright "sun" patch, written as EXR.
  const int w = 64, h = 32;
  std::vector<float> px(static_cast<size_t>(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float* p = &px[3 * (static_cast<size_t>(y) * w + x)];
      p[0] = 0.2f + 0.3f * y / h;
      p[1] = 0.3f;
      p[2] = 0.6f - 0.4f * y / h;
      if (x >= 40 && x < 43 && y >= 8 && y < 10) p[0] = p[1] = p[2] = 500.0f;
    }
  write_image(dir.path() / "sky.exr", w, h, px, ToneMap{});
  const std::string json = R"({
    "camera": {"position": [0, 1, 0.0001], "look_at": [0, 0, 0], "fov": 0.5, "resolution": [4, 4]},
    "render": {"max_depth": 1},
    "materials": {"m": {"type": "diffuse", "albedo": 0.5}},
    "shapes": [{"type": "quad", "material": "m", "vertices": [[-0.1, 0, 0.1], [0.1, 0, 0.1], [0.1, 0, -0.1], [-0.1, 0, -0.1]]}],
    "lights": [{"type": "environment", "file": "sky.exr", "scale": 0.5, "rotate": 30}] })";
  const TestRender t = render_json(json, 1024, 0, 0, dir.path());
  const auto* env = t.scene->infinite_lights().at(0);
  // Quadrature over the upper hemisphere in (cos theta, phi), fine enough to resolve the sun.
  const int nt = 2048, np = 4096;
  Vec3d acc(0.0);
  for (int i = 0; i < nt; ++i) {
    const double ct = (i + 0.5) / nt;
    const double st = std::sqrt(1 - ct * ct);
    for (int j = 0; j < np; ++j) {
      const double phi = 2 * M_PI * (j + 0.5) / np;
      const Vec3 wdir(static_cast<float>(st * std::cos(phi)), static_cast<float>(ct),
                      static_cast<float>(st * std::sin(phi)));
      acc += Vec3d(env->eval(LightHit{wdir})) * ct;
    }
  }
  const Vec3d integral = acc * (2 * M_PI / (static_cast<double>(nt) * np));
  // The quad is only 0.2 wide: the whole scene is the upper hemisphere's view.
  expect_near_rgb(image_stats(t.film), Rgb(integral * (0.5 / M_PI)), 2e-3, "environment map");
}

}  // namespace
}  // namespace kozu::test
