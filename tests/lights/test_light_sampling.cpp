// Light sampling: chi-square of each light's sampled directions against its own pdf, seen from a
// reference point, plus power and selection checks.
#include "support/chi2.h"
#include "support/render_test.h"

#include "core/frame.h"
#include "core/rng.h"
#include "core/warp.h"
#include "io/image_io.h"
#include "lights/area.h"
#include "lights/environment.h"
#include "lights/light_sampler.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace kozu::test {
namespace {

constexpr int kChi2Tests = 7;

Chi2Options options(int integration_points = 8) {
  Chi2Options o;
  o.test_count = kChi2Tests;
  o.integration_points = integration_points;
  return o;
}

// An area light alone in a scene; its pdf for a direction comes from a real ray hit.
struct AreaLightFixture {
  std::unique_ptr<Scene> scene;
  const Light* light;
  explicit AreaLightFixture(const std::string& shape_json) {
    scene = load_scene_text(fmt::format(R"({{"camera": {{"position": [0, 0, -5], "look_at": [0, 0, 0]}},
      "shapes": [{}]}})",
                                        shape_json),
                            "scene.json", ".");
    light = scene->lights.at(0).get();
  }
  Chi2Result run(const LightSampleContext& ctx, const Chi2Options& opt) const {
    return chi2_test(
        [&](const Vec2& u) -> std::optional<Vec3> {
          const LightSample ls = light->sample(ctx, u);
          if (!ls.valid()) return std::nullopt;
          return ls.wi;
        },
        [&](const Vec3& w) -> double {
          SurfaceInteraction si;
          if (!scene->intersect(Ray{ctx.p, w, kInfinity}, si)) return 0.0;
          return light->pdf(ctx, LightHit{w, &si});
        },
        opt);
  }
};

TEST(AreaLightChi2, SphereCone) {
  // Sphere on the +z axis seen from the origin: the sampled cone is narrow, so bin only the cap.
  AreaLightFixture f(R"({"type": "sphere", "center": [0, 0, 3], "radius": 1, "emission": 1})");
  Chi2Options opt = options(16);
  opt.cos_theta_min = 0.9;      // the cone's cos(theta_max) = sqrt(1 - 1/9) = 0.943
  opt.check_lost_mass = false;  // the silhouette cuts cells; its quadrature is not 1e-5 exact
  const Chi2Result r = f.run({Vec3(0.0f), Vec3(0.0f)}, opt);
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_integral, 1.0, 2e-3);
}

TEST(AreaLightChi2, SphereFromInside) {
  AreaLightFixture f(R"({"type": "sphere", "center": [0, 0, 0.3], "radius": 1, "emission": 1, "two_sided": true})");
  const Chi2Result r = f.run({Vec3(0.0f), Vec3(0.0f)}, options());
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_integral, 1.0, 1e-3);
}

// The polygon and triangle lights' chi-square, seen from `from`: 16 integration points per cell, and no lost-mass
// check (cells the silhouette cuts are not integrated 1e-5 exactly).
void expect_area_light_chi2(const std::string& shape_json, const Vec3& from) {
  const AreaLightFixture f(shape_json);
  Chi2Options opt = options(16);
  opt.check_lost_mass = false;
  const Chi2Result r = f.run({from, Vec3(0.0f)}, opt);
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_integral, 1.0, 2e-3);
}

TEST(AreaLightChi2, QuadByArea) {
  expect_area_light_chi2(
      R"({"type": "quad", "emission": 1, "vertices": [[-1, -0.5, 1], [1, -0.5, 1], [1, 1.5, 1], [-1, 1.5, 1]]})",
      Vec3(0.0f));
}

// A textured quad samples points in proportion to the texture's luminance (plus a floor): a checker whose
// colours are 20:1 apart, against its own pdf; its power is π A times the texture's mean.
constexpr const char* kCheckerQuad =
    R"({"type": "quad", "emission": {"type": "checker", "scale": [3, 2], "a": [4, 2, 1], "b": [0.1, 0.2, 0.2]},
        "vertices": [[-1, -0.5, 1], [1, -0.5, 1], [1, 1.5, 1.4], [-1, 1.5, 1.4]]})";

TEST(AreaLightChi2, TexturedQuadByLuminance) { expect_area_light_chi2(kCheckerQuad, Vec3(0.0f)); }

TEST(AreaLightChi2, TexturedQuadPowerAndRadiance) {
  AreaLightFixture f(kCheckerQuad);
  // Area 2 × |(0, 2, 0.4)|; the checker (3 × 2 checks) is half a, half b.
  const float area = 2.0f * std::sqrt(4.0f + 0.16f);
  const Rgb mean = 0.5f * (Rgb(4, 2, 1) + Rgb(0.1f, 0.2f, 0.2f));
  const Rgb power = f.light->power();
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(power[c], kPi * area * mean[c], 1e-3f * power[c]);
  // A sample's radiance is the texture at its point: the check with lower corner (0, 0) is a (seen from the front,
  // +z; the back of the one-sided light is black).
  EXPECT_TRUE(is_black(f.light->sample({Vec3(0.0f), Vec3(0.0f)}, Vec2(0.05f, 0.05f)).radiance));
  const LightSample ls = f.light->sample({Vec3(0.0f, 0.0f, 3.0f), Vec3(0.0f)}, Vec2(0.05f, 0.05f));
  ASSERT_TRUE(ls.valid());
  const Rgb& v = ls.radiance;
  EXPECT_TRUE((v.r == 4.0f && v.g == 2.0f && v.b == 1.0f)) << v.r << " " << v.g << " " << v.b;
}

TEST(AreaLightChi2, NonConvexPolygon) {
  expect_area_light_chi2(
      R"({"type": "polygon", "emission": 1, "vertices": [[0, 0, 1], [2, 0, 1], [2, 1, 1], [1, 1, 1], [1, 2, 1], [0, 2, 1]]})",
      Vec3(-0.5f, -0.5f, 0.0f));
}

TEST(AreaLightChi2, MeshTriangle) {
  expect_area_light_chi2(
      R"({"type": "mesh", "emission": 1, "positions": [[-1, 0, 0.5], [1, -0.2, 0.8], [0, 1.5, 1.5]], "indices": [0, 1, 2]})",
      Vec3(0.0f));
}

TEST(EnvironmentChi2, UniformCosineAroundNormal) {
  EnvironmentLight env(Rgb(1.0f));
  const LightSampleContext ctx{Vec3(0.0f), glm::normalize(Vec3(0.3f, -0.2f, 0.9f))};
  const Chi2Result r = chi2_test(
      [&](const Vec2& u) -> std::optional<Vec3> {
        const LightSample ls = env.sample(ctx, u);
        if (!ls.valid()) return std::nullopt;
        return ls.wi;
      },
      [&](const Vec3& w) { return static_cast<double>(env.pdf(ctx, LightHit{w})); }, options());
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_integral, 1.0, 1e-3);
}

// The lat-long map is tested in its own (u, v) parameterisation, with chi-square cells aligned to
// its pixels so the piecewise-constant density is integrated exactly. The density in (u, v) is
// pdf(omega) * 2 pi^2 sin(theta), mapping directions back with the documented convention.
TEST(EnvironmentChi2, ImageImportanceSampling) {
  const int w = 16, h = 8;
  std::vector<Rgb> px(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) px[static_cast<size_t>(y) * w + x] = Rgb(0.1f + (x * 7 + y * 3) % 11, 1.0f, 0.5f + y);
  px[3 * w + 5] = Rgb(400.0f);  // a sun
  // MIS-compensated (the default: half the cells below the mean, of density 0) and not.
  for (const bool compensate : {true, false}) {
  SCOPED_TRACE(compensate ? "compensated" : "uncompensated");
  EnvironmentLight env(px, w, h, 1.0f, 0.0f, compensate);
  EXPECT_EQ(env.compensated(), compensate);
  const LightSampleContext ctx{Vec3(0.0f), Vec3(0.0f)};
  auto to_uv = [](const Vec3& d) { return Vec2(0.5f + std::atan2(d.x, -d.z) * kInv2Pi, safe_acos(d.y) * kInvPi); };
  Chi2Grid2D grid;
  grid.x_bins = 2 * w;
  grid.y_bins = 2 * h;
  const Chi2Result r = chi2_test_2d(
      [&](const Vec2& u) -> std::optional<Vec2> {
        const LightSample ls = env.sample(ctx, u);
        if (!ls.valid()) return std::nullopt;
        return glm::clamp(to_uv(ls.wi), Vec2(0.0f), Vec2(kOneMinusEpsilon));
      },
      [&](const Vec2& uv) -> double {
        const float theta = uv.y * kPi, phi = (uv.x - 0.5f) * kTwoPi;
        const Vec3 d(std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi));
        return env.pdf(ctx, LightHit{d}) * 2.0 * kPi * kPi * std::sin(theta);
      },
      grid, options());
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_integral, 1.0, 1e-3);
  }
}

// eval_pdf (what a BSDF ray that escapes asks) gives exactly eval's radiance and pdf's density, and at the directions
// sample() draws it gives the radiance and density sample() gave (the MIS weights of the two strategies must agree),
// turned or not. Away from the poles within 1e-4 relative: both take sin θ from the direction, sample() from θ.
TEST(EnvironmentLight, EvalPdfAgreesWithEvalPdfAndSample) {
  const int w = 16, h = 8;
  std::vector<Rgb> px(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) px[static_cast<size_t>(y) * w + x] = Rgb(0.1f + (x * 7 + y * 3) % 11, 1.0f, 0.5f + y);
  px[3 * w + 5] = Rgb(400.0f);
  Pcg32 rng(5);
  for (const float deg : {0.0f, 37.0f}) {
    const EnvironmentLight env(px, w, h, 1.0f, deg);
    const LightSampleContext ctx{Vec3(0.0f), Vec3(0.0f)};
    int compared = 0;
    for (int i = 0; i < 20000; ++i) {
      const Vec2 u(rng.next_float(), rng.next_float());
      const LightHit any{warp::square_to_uniform_sphere(u)};
      float p = -1.0f;
      const Rgb L = env.eval_pdf(ctx, any, &p);
      ASSERT_EQ(L, env.eval(any));
      ASSERT_EQ(p, env.pdf(ctx, any));
      const LightSample ls = env.sample(ctx, u);
      if (!ls.valid() || std::abs(ls.wi.y) > 0.995f) continue;
      const Rgb Ls = env.eval_pdf(ctx, LightHit{ls.wi}, &p);
      EXPECT_NEAR(p / ls.pdf, 1.0f, 1e-4f) << "at " << ls.wi.x << " " << ls.wi.y << " " << ls.wi.z;
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(Ls[c], ls.radiance[c], 1e-4f * (1.0f + ls.radiance[c]));
      ++compared;
    }
    EXPECT_GT(compared, 15000);
  }
}

// eval is the bilinear lookup of the image at the direction's (u, v), wrapping in u across the seam behind the
// camera and clamping in v at the poles: against a plain reference (integer modulo) at 4000 directions, u and v from
// every part of the image, the seam's and the poles' half-pixel bands included.
TEST(EnvironmentLight, EvalIsBilinearWrappingInU) {
  const int w = 16, h = 8;
  std::vector<Rgb> px(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) px[static_cast<size_t>(y) * w + x] = Rgb(float(x), float(y), float((x * 5 + y) % 7));
  const EnvironmentLight env(px, w, h, 1.0f, 0.0f);
  const auto at = [&](int x, int y) {
    x = ((x % w) + w) % w;
    y = std::clamp(y, 0, h - 1);
    return px[static_cast<size_t>(y) * w + x];
  };
  Pcg32 rng(5);
  double worst = 0.0;
  for (int i = 0; i < 4000; ++i) {
    const Vec2 uv(i < 200 ? 0.5f / w * rng.next_float() : (i < 400 ? 1.0f - 0.5f / w * rng.next_float() : rng.next_float()),
                  0.02f + 0.96f * rng.next_float());
    const float theta = uv.y * kPi, phi = (uv.x - 0.5f) * kTwoPi;
    const Vec3 d(std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi));
    // The (u, v) eval sees, from the direction as the renderer maps it (float rounding moves it slightly).
    const Vec2 seen(0.5f + std::atan2(d.x, -d.z) * kInv2Pi, safe_acos(d.y) * kInvPi);
    const float x = seen.x * w - 0.5f, y = seen.y * h - 0.5f;
    const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
    const float fx = x - x0, fy = y - y0;
    const Rgb expected = (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
                         fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
    const Rgb got = env.eval(LightHit{d});
    for (int c = 0; c < 3; ++c) worst = std::max(worst, double(std::abs(got[c] - expected[c])));
  }
  EXPECT_LT(worst, 2e-3) << "largest difference from the reference";
}

// Light sampling must cover what eval returns: the bilinear lookup spreads a one-pixel sun half-way into the pixels
// around it, so their cells need density too, or BSDF samples that hit them carry the sun unweighted (fireflies).
// Over directions away from the poles (where the cells' sin(theta) varies most), radiance / pdf stays within a
// small factor of the total: 16 for the corner cells of a bilinear footprint (a quarter of the sun over a 1/64
// mean), times sin(theta)'s change across a cell. With the cell's own pixel as its importance, the cells beside
// the sun had ratios of 10^6.
// MIS-compensated, the cells below the map's mean have density 0 (their light is the BSDF samples'), and the bound
// holds where the radiance is above 8 times the mean (a cell of mean below the map's can reach 4 times it at a
// corner of its bilinear lookup): every cell the sun's lookup reaches keeps its density.
TEST(EnvironmentLight, DensityCoversTheBilinearLookup) {
  const int w = 32, h = 16;
  std::vector<Rgb> px(static_cast<size_t>(w) * h, Rgb(1e-3f));
  px[6 * w + 11] = Rgb(1e4f);  // a sun
  for (const bool compensate : {false, true}) {
    SCOPED_TRACE(compensate ? "compensated" : "uncompensated");
    EnvironmentLight env(px, w, h, 1.0f, 0.0f, compensate);
    const LightSampleContext ctx{Vec3(0.0f), Vec3(0.0f)};
    const int n = 512;
    double integral = 0.0, worst = 0.0;
    std::vector<std::pair<double, double>> ratios;  // (luminance, pdf)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < 2 * n; ++i) {
        const float theta = kPi * (j + 0.5f) / n, phi = kTwoPi * (i + 0.5f) / (2 * n);
        const Vec3 d(std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi));
        const double L = luminance(env.eval(LightHit{d}));
        integral += L * std::sin(theta) * (kPi / n) * (kPi / n);
        if (std::abs(d.y) < 0.9f) ratios.emplace_back(L, env.pdf(ctx, LightHit{d}));
      }
    const double mean = integral / (4.0 * kPi);
    size_t covered = 0, zero = 0;
    for (const auto& [L, pdf] : ratios) {
      if (compensate && L <= 8.0 * mean) {
        zero += pdf == 0.0;
        continue;
      }
      ASSERT_GT(pdf, 0.0) << L / mean << " times the mean";
      worst = std::max(worst, L / pdf);
      ++covered;
    }
    EXPECT_GT(covered, 0u);
    EXPECT_LT(worst / integral, 32.0);
    // Compensated, the dim background is left to the BSDF samples.
    if (compensate) {
      EXPECT_GT(zero, ratios.size() * 9 / 10);
    }
  }
}

// "rotate" turns the image about +y the way a shape's "rotate": [0, 1, 0, deg] turns a shape (right-handed): a
// sun the unturned image shows towards d is seen towards R d, and sampling finds it there too. (It turned the
// other way before.)
TEST(EnvironmentLight, RotateTurnsTheImageLikeAShapesRotate) {
  const int w = 16, h = 8;
  std::vector<Rgb> px(static_cast<size_t>(w) * h, Rgb(0.01f));
  px[3 * w + 5] = Rgb(1000.0f);  // a sun
  EnvironmentLight still(px, w, h, 1.0f, 0.0f);
  const LightSampleContext ctx{Vec3(0.0f), Vec3(0.0f)};
  // The sun's direction in the unturned image: the mean sampled direction, almost all samples land on it.
  const auto sun_of = [&](const EnvironmentLight& env) {
    Vec3 sum(0.0f);
    for (int i = 0; i < 64; ++i)
      for (int j = 0; j < 64; ++j) {
        const LightSample ls = env.sample(ctx, Vec2((i + 0.5f) / 64.0f, (j + 0.5f) / 64.0f));
        if (ls.valid() && max_component(env.eval(LightHit{ls.wi})) > 100.0f) sum += ls.wi;
      }
    return glm::normalize(sum);
  };
  const Vec3 d = sun_of(still);
  for (const float deg : {90.0f, -40.0f}) {
    EnvironmentLight turned(px, w, h, 1.0f, deg);
    const Vec3 expected = Transform::rotate(Vec3(0, 1, 0), deg).vector(d);
    EXPECT_GT(max_component(turned.eval(LightHit{expected})), 100.0f) << deg;
    EXPECT_LT(max_component(turned.eval(LightHit{d})), 1.0f) << deg;
    EXPECT_NEAR(glm::dot(sun_of(turned), expected), 1.0f, 1e-4f) << deg;
  }
}

TEST(LightSampler, SelectionIsProportionalToPower) {
  auto scene = load_scene_text(R"({"camera": {"position": [0, 0, -5], "look_at": [0, 0, 0]},
    "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "emission": 1},
               {"type": "quad", "emission": [3, 0, 0], "vertices": [[2, 0, 0], [3, 0, 0], [3, 1, 0], [2, 1, 0]]}],
    "lights": [{"type": "point", "position": [0, 5, 0], "intensity": 2}]})",
                               "scene.json", ".");
  const LightSampler& ls = scene->light_sampler();
  // Powers (RGB average): sphere pi * 4 pi * 1, quad pi * 1 * 1, point 4 pi * 2.
  const double p[3] = {4 * M_PI * M_PI, M_PI, 8 * M_PI};
  const double total = p[0] + p[1] + p[2];
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(ls.pmf(scene->lights[i].get()), p[i] / total, 1e-6);
  // Sampled frequencies match the pmf.
  std::vector<double> observed(3, 0.0), expected(3);
  Pcg32 rng(3);
  constexpr int kN = 300000;
  for (int i = 0; i < kN; ++i) {
    float pmf;
    const Light* l = ls.sample(rng.next_float(), &pmf);
    observed[l->index] += 1;
  }
  for (int i = 0; i < 3; ++i) expected[i] = kN * p[i] / total;
  const Chi2Result r = chi2_test_counts(observed, expected, options());
  EXPECT_TRUE(r.passed) << r.message;
}

// A map without contrast has nothing above its mean: it keeps its importance (compensated() false), and its density
// is the uniform sphere's.
TEST(EnvironmentLight, AMapWithoutContrastIsNotCompensated) {
  const int w = 16, h = 8;
  const EnvironmentLight env(std::vector<Rgb>(static_cast<size_t>(w) * h, Rgb(0.7f)), w, h, 1.0f, 0.0f, true);
  EXPECT_FALSE(env.compensated());
  const LightSampleContext ctx{Vec3(0.0f), Vec3(0.0f)};
  for (const Vec3& d : {glm::normalize(Vec3(0.2f, 1, 0)), Vec3(1, 0, 0), glm::normalize(Vec3(1, -2, 3))})
    EXPECT_NEAR(env.pdf(ctx, LightHit{d}), kInv4Pi, 0.05 * kInv4Pi) << d.x << " " << d.y << " " << d.z;
}

// A product shot's light, 128 x 64: a dim studio (0.08, a warm floor bounce of 0.18 below the horizon) with a softbox
// of radiance 12 and a strip of 6.
float studio(int x, int y, int w, int h) {
  const float theta = kPi * (y + 0.5f) / h, phi = kTwoPi * ((x + 0.5f) / w - 0.5f);
  const Vec3 d(std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi));
  if (d.x < -0.35f && d.y > 0.35f && std::abs(d.z) < 0.5f) return 12.0f;
  if (d.x > 0.8f && std::abs(d.y - 0.2f) < 0.25f && std::abs(d.z) < 0.3f) return 6.0f;
  return d.y < 0.0f ? 0.18f : 0.08f;
}

// Direct light on an open white Lambertian point under the studio, as the path tracer estimates it: one light sample
// and one cosine-weighted BSDF sample under the power heuristic. MIS-compensated, the light's density is 0 wherever
// the map is below its mean, and the BSDF samples alone take that light: the estimate's mean is still the quadrature's,
// for each of three normals, and its variance is lower.
TEST(EnvironmentLight, CompensatedMisIsUnbiasedWithLessVariance) {
  const int w = 128, h = 64;
  std::vector<Rgb> px(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) px[static_cast<size_t>(y) * w + x] = Rgb(studio(x, y, w, h));
  const EnvironmentLight on(px, w, h, 1.0f, 0.0f, true), off(px, w, h, 1.0f, 0.0f, false);
  ASSERT_TRUE(on.compensated());
  // (normal, the variance's least ratio): measured 1.91 facing up, 1.77 facing the softbox, 1.02 facing the strip,
  // where the dim studio is a small part of what the point sees.
  for (const auto& [normal, ratio] : {std::pair(Vec3(0, 1, 0), 1.5), std::pair(glm::normalize(Vec3(-1, 1, 0.3f)), 1.5),
                                      std::pair(glm::normalize(Vec3(1, 0.2f, -0.5f)), 1.0)}) {
    const Vec3 n = normal;  // a plain variable: clang 14 does not let a lambda capture a structured binding
    SCOPED_TRACE(fmt::format("normal ({:.2f}, {:.2f}, {:.2f})", n.x, n.y, n.z));
    const LightSampleContext ctx{Vec3(0.0f), n};
    const Frame frame(n);
    // Outgoing radiance, the integral of L cos / pi over the hemisphere, by the midpoint rule in (cos θ, φ).
    double expected = 0.0;
    constexpr int kSteps = 1000;
    for (int a = 0; a < kSteps; ++a)
      for (int b = 0; b < kSteps; ++b) {
        const float z = (a + 0.5f) / kSteps, phi = kTwoPi * (b + 0.5f) / kSteps, r = std::sqrt(1.0f - z * z);
        const Vec3 wi = frame.to_world(Vec3(r * std::cos(phi), r * std::sin(phi), z));
        expected += luminance(on.eval(LightHit{wi})) * z * kInvPi * (kTwoPi / (double(kSteps) * kSteps));
      }
    const auto estimate = [&](const EnvironmentLight& env, double* variance) {
      Pcg32 rng(5);
      double sum = 0.0, sum2 = 0.0;
      constexpr int kN = 400000;
      for (int i = 0; i < kN; ++i) {
        double x = 0.0;
        const LightSample ls = env.sample(ctx, Vec2(rng.next_float(), rng.next_float()));
        const float cos_l = ls.valid() ? glm::dot(ls.wi, n) : 0.0f;
        if (cos_l > 0.0f)
          x += luminance(ls.radiance) * cos_l * kInvPi / ls.pdf * power_heuristic(ls.pdf, cos_l * kInvPi);
        const Vec3 local = warp::square_to_cosine_hemisphere(Vec2(rng.next_float(), rng.next_float()));
        if (local.z > 0.0f) {
          const Vec3 wi = frame.to_world(local);
          const float pdf_b = local.z * kInvPi;
          x += luminance(env.eval(LightHit{wi})) * power_heuristic(pdf_b, env.pdf(ctx, LightHit{wi}));
        }
        sum += x;
        sum2 += x * x;
      }
      const double mean = sum / kN;
      *variance = sum2 / kN - mean * mean;
      return std::pair(mean, std::sqrt(*variance / kN));
    };
    double var_on = 0.0, var_off = 0.0;
    const auto [mean_on, se_on] = estimate(on, &var_on);
    const auto [mean_off, se_off] = estimate(off, &var_off);
    EXPECT_NEAR(mean_on, expected, 4.0 * se_on + 1e-3 * expected);
    EXPECT_NEAR(mean_off, expected, 4.0 * se_off + 1e-3 * expected);
    EXPECT_LT(var_on * ratio, var_off) << var_on << " against " << var_off;
  }
}

// The same in a render, with shadows and a second bounce: a diffuse floor, a diffuse and a rough metal sphere. The
// MIS-compensated image's mean is the uncompensated one's (within the two renders' noise).
TEST(EnvironmentLight, CompensatedRenderKeepsTheMean) {
  TempDir dir;
  const int w = 128, h = 64;
  write_test_exr(dir.path() / "studio.exr", w, h, [&](int x, int y, int) { return studio(x, y, w, h); });
  const auto render = [&](bool compensate, uint64_t seed) {
    const std::string json = fmt::format(R"({{
      "camera": {{"position": [0, 1.2, 4], "look_at": [0, 0.5, 0], "fov": 40, "resolution": [24, 24]}},
      "render": {{"max_depth": 2, "filter": "box"}},
      "materials": {{"floor": {{"type": "diffuse", "albedo": 0.5}},
                     "metal": {{"type": "conductor", "roughness": 0.3}}}},
      "shapes": [
        {{"type": "quad", "material": "floor", "vertices": [[-5, 0, -5], [-5, 0, 5], [5, 0, 5], [5, 0, -5]]}},
        {{"type": "sphere", "material": "floor", "center": [-0.6, 0.5, 0], "radius": 0.5}},
        {{"type": "sphere", "material": "metal", "center": [0.6, 0.5, 0], "radius": 0.5}}],
      "lights": [{{"type": "environment", "file": "{}", "mis_compensation": {}}}] }})",
                                         (dir.path() / "studio.exr").string(), compensate);
    return image_stats(render_json(json, 64, 0, seed).film);
  };
  const ImageStats on = render(true, 1), off = render(false, 2);
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(on.mean[c], off.mean[c], 4.0 * std::hypot(on.standard_error[c], off.standard_error[c]))
        << "channel " << c;
}

}  // namespace
}  // namespace kozu::test
