// Portal-masked environment sampling (lights/environment_portal.h; Bitterli, Novák and Jarosz 2015): chi-square of
// the rectified sampler against its own density, the density's integral over the window by quadrature, the
// irradiance through one and two windows against quadrature, the map's sampling kept outside, the scene key's
// errors, and a room lit through its window rendered with and without the portal.
#include "support/chi2.h"
#include "support/render_test.h"

#include "core/rng.h"
#include "lights/environment.h"
#include "lights/environment_portal.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>

namespace kozu::test {
namespace {

// A sky on the -z side: a gradient and a sun (luminance about 40 over a 4-degree spot), positive everywhere.
float sky(const Vec3& w) {
  const Vec3 sun = glm::normalize(Vec3(0.2f, 0.1f, -1.0f));
  return 0.3f + 0.2f * w.x + 40.0f * std::exp(-glm::dot(w - sun, w - sun) / 0.005f);
}

// The portal [0, W] x [0, H] in the plane z = 0, its front (corners counter-clockwise seen from +z) towards the
// scene at z > 0: its frame is x = +x, y = +y, z (towards the environment) = -z.
std::array<Vec3, 4> rectangle(float W, float H) { return {Vec3(0, 0, 0), Vec3(W, 0, 0), Vec3(W, H, 0), Vec3(0, H, 0)}; }

// The rectified coordinates' Jacobian dω / (dα dβ), in its trigonometric form (the code uses the direction's).
double jacobian(double alpha, double beta) {
  const double ta = std::tan(alpha), tb = std::tan(beta);
  return (1 + ta * ta) * (1 + tb * tb) / std::pow(1 + ta * ta + tb * tb, 1.5);
}

// The sampler's density in the table's cell coordinates, on a grid whose cells are the table's (halved), so the
// piecewise-constant density is integrated exactly: the window's edges are placed on cell edges by choosing the
// point and the window's size from the cells.
TEST(EnvironmentPortal, Chi2InRectifiedCoordinates) {
  constexpr int n = 32;
  const double cell = M_PI / n;
  const int k0 = 10, k1 = 22, m0 = 12, m1 = 20;
  const double h = 1.0;
  const double lx = -h * std::tan(k0 * cell - M_PI / 2), ly = -h * std::tan(m0 * cell - M_PI / 2);
  const double W = lx + h * std::tan(k1 * cell - M_PI / 2), H = ly + h * std::tan(m1 * cell - M_PI / 2);
  const EnvironmentPortal portal(rectangle(float(W), float(H)), sky, n);
  const Vec3 p(static_cast<float>(lx), static_cast<float>(ly), static_cast<float>(h));
  const EnvironmentPortal::View v = portal.view(p);
  ASSERT_FALSE(v.empty());
  EXPECT_NEAR(v.x0, k0, 1e-4);
  EXPECT_NEAR(v.x1, k1, 1e-4);
  EXPECT_NEAR(v.y0, m0, 1e-4);
  EXPECT_NEAR(v.y1, m1, 1e-4);
  const auto to_cells = [&](const Vec3& w) {
    // The frame's z is -z: α = atan(w.x / -w.z).
    return Vec2(float((std::atan2(double(w.x), -double(w.z)) + M_PI / 2) / cell),
                float((std::atan2(double(w.y), -double(w.z)) + M_PI / 2) / cell));
  };
  Chi2Grid2D grid;
  grid.x0 = k0;
  grid.x1 = k1;
  grid.y0 = m0;
  grid.y1 = m1;
  grid.x_bins = 2 * (k1 - k0);
  grid.y_bins = 2 * (m1 - m0);
  Chi2Options o;
  o.test_count = 2;
  const Chi2Result r = chi2_test_2d(
      [&](const Vec2& u) -> std::optional<Vec2> {
        float pdf = 0.0f;
        const Vec3 w = portal.sample(v, u, &pdf);
        if (!(pdf > 0.0f)) return std::nullopt;
        return to_cells(w);
      },
      [&](const Vec2& xy) -> double {
        const double alpha = xy.x * cell - M_PI / 2, beta = xy.y * cell - M_PI / 2;
        const Vec3 w = glm::normalize(Vec3(float(std::tan(alpha)), float(std::tan(beta)), -1.0f));
        return portal.pdf(v, w) * jacobian(alpha, beta) * cell * cell;
      },
      grid, o);
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_integral, 1.0, 1e-3);
}

// The same in solid angle, from points whose view of the window falls anywhere on the cells (one close to the
// window's plane, which sees it over most of the hemisphere): the density integrates to 1 over the sphere, and every
// sample's density is pdf()'s at its direction.
TEST(EnvironmentPortal, DensityIntegratesToOneOverTheWindowAndMatchesSample) {
  const float W = 1.3f, H = 0.7f;
  const EnvironmentPortal portal(rectangle(W, H), sky, 96);
  for (const Vec3 p : {Vec3(0.4f, 0.2f, 0.9f), Vec3(-2.0f, 1.5f, 0.3f), Vec3(0.6f, 0.3f, 0.02f)}) {
    const EnvironmentPortal::View v = portal.view(p);
    ASSERT_FALSE(v.empty());
    // Over the hemisphere towards the environment (-z) in (cos θ, φ), which knows nothing of the rectified cells;
    // directions that miss the window have density 0.
    constexpr int kTheta = 2000, kPhi = 4000;
    double sum = 0.0;
    for (int a = 0; a < kTheta; ++a)
      for (int b = 0; b < kPhi; ++b) {
        const double cos_t = (a + 0.5) / kTheta, phi = 2.0 * M_PI * (b + 0.5) / kPhi;
        const double sin_t = std::sqrt(1.0 - cos_t * cos_t);
        sum += portal.pdf(v, Vec3(Vec3d(sin_t * std::cos(phi), sin_t * std::sin(phi), -cos_t)));
      }
    EXPECT_NEAR(sum * (1.0 / kTheta) * (2.0 * M_PI / kPhi), 1.0, 2e-3) << "from " << p.x << " " << p.y << " " << p.z;
    Pcg32 rng(3);
    int agree = 0;
    constexpr int kSamples = 20000;
    for (int i = 0; i < kSamples; ++i) {
      float pdf = 0.0f;
      const Vec3 w = portal.sample(v, Vec2(rng.next_float(), rng.next_float()), &pdf);
      ASSERT_GT(pdf, 0.0f);
      ASSERT_LT(w.z, 0.0f);  // towards the environment
      // Through the window: the ray from p meets z = 0 inside the rectangle.
      const float t = -p.z / w.z;
      const Vec3 q = p + t * w;
      ASSERT_GE(q.x, -1e-4f * W);
      ASSERT_LE(q.x, W * (1 + 1e-4f));
      ASSERT_GE(q.y, -1e-4f * H);
      ASSERT_LE(q.y, H * (1 + 1e-4f));
      if (std::abs(portal.pdf(v, w) / pdf - 1.0f) < 1e-3f) ++agree;
    }
    // A sample within rounding of a cell's edge may read its neighbour's density back.
    EXPECT_GT(agree, kSamples * 998 / 1000);
  }
}

// From the environment's side of the plane, or within it, the portal is empty.
TEST(EnvironmentPortal, EmptyFromBehindAndFromItsPlane) {
  const EnvironmentPortal portal(rectangle(1.0f, 1.0f), sky, 16);
  EXPECT_TRUE(portal.view(Vec3(0.5f, 0.5f, -0.5f)).empty());
  EXPECT_TRUE(portal.view(Vec3(0.5f, 0.5f, 0.0f)).empty());
  EXPECT_FALSE(portal.view(Vec3(0.5f, 0.5f, 0.5f)).empty());
  // A black sky has nothing to sample.
  const EnvironmentPortal dark(rectangle(1.0f, 1.0f), [](const Vec3&) { return 0.0f; }, 16);
  EXPECT_TRUE(dark.view(Vec3(0.5f, 0.5f, 0.5f)).empty());
}

// A lat-long map with a sun (radiance 400 in one texel) over a gradient, for EnvironmentLight.
std::vector<Rgb> map_with_sun(int w, int h) {
  std::vector<Rgb> px(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) px[static_cast<size_t>(y) * w + x] = Rgb(0.2f + 0.01f * x, 0.5f, 0.3f + 0.02f * y);
  px[static_cast<size_t>(h / 3) * w + w / 4 + 3] = Rgb(400.0f);
  return px;
}

// Windows in the walls x = 3 (facing -x, into the room) and z = 2 (facing -z): a quad light's order, front inward.
const std::array<Vec3, 4> kWindowX{Vec3(3, 0.9f, -0.8f), Vec3(3, 0.9f, 0.8f), Vec3(3, 2.1f, 0.8f), Vec3(3, 2.1f, -0.8f)};
const std::array<Vec3, 4> kWindowZ{Vec3(-1, 1, 2), Vec3(-1, 2, 2), Vec3(0, 2, 2), Vec3(0, 1, 2)};

// The irradiance at a point of the floor from what it sees through the windows, ∫ L cos θ dω, by quadrature over the
// windows' areas, against the estimator L cos θ / pdf of the light's samples (which never leave the windows).
// Map sampling restricted to the windows (samples elsewhere count 0, as a wall would stop them) is the control: the
// same mean, far more variance.
TEST(EnvironmentPortal, IrradianceThroughWindowsMatchesQuadrature) {
  const int w = 64, h = 32;
  // The control estimates by light samples alone: uncompensated, whose density covers the whole sky.
  EnvironmentLight map(map_with_sun(w, h), w, h, 1.0f, 20.0f, false);
  const LightSampleContext ctx{Vec3(0.5f, 0.0f, 0.4f), Vec3(0, 1, 0)};
  for (const int windows : {1, 2}) {
    std::vector<std::array<Vec3, 4>> corners{kWindowX};
    if (windows == 2) corners.push_back(kWindowZ);
    EnvironmentLight env(map_with_sun(w, h), w, h, 1.0f, 20.0f);
    env.set_portals(corners);
    ASSERT_EQ(env.portal_count(), size_t(windows));
    double expected = 0.0;
    for (const auto& c : corners) {
      const Vec3d e1 = Vec3d(c[1] - c[0]), e3 = Vec3d(c[3] - c[0]);
      const double area = glm::length(glm::cross(e1, e3));
      constexpr int kSteps = 600;
      for (int a = 0; a < kSteps; ++a)
        for (int b = 0; b < kSteps; ++b) {
          const Vec3d q = Vec3d(c[0]) + (a + 0.5) / kSteps * e1 + (b + 0.5) / kSteps * e3;
          const Vec3d d = q - Vec3d(ctx.p);
          const double r2 = glm::dot(d, d);
          const Vec3 wi(glm::normalize(d));
          const double cos_q = std::abs(glm::dot(glm::normalize(glm::cross(e1, e3)), Vec3d(wi)));
          expected += luminance(env.eval(LightHit{wi})) * std::max(0.0f, wi.y) * cos_q / r2 * area /
                      (double(kSteps) * kSteps);
        }
    }
    const auto through = [&](const Vec3& wi) {
      for (const auto& c : corners) {
        const Vec3 n = glm::normalize(glm::cross(c[1] - c[0], c[2] - c[0]));
        const float t = glm::dot(c[0] - ctx.p, n) / glm::dot(wi, n);
        if (!(t > 0.0f)) continue;
        const Vec3 q = ctx.p + t * wi - c[0];
        const float s = glm::dot(q, c[1] - c[0]) / glm::dot(c[1] - c[0], c[1] - c[0]);
        const float r = glm::dot(q, c[3] - c[0]) / glm::dot(c[3] - c[0], c[3] - c[0]);
        if (s >= 0 && s <= 1 && r >= 0 && r <= 1) return true;
      }
      return false;
    };
    const auto estimate = [&](const EnvironmentLight& light, bool restrict, double* variance) {
      Pcg32 rng(11);
      double sum = 0.0, sum2 = 0.0;
      constexpr int kN = 200000;
      for (int i = 0; i < kN; ++i) {
        const LightSample ls = light.sample(ctx, Vec2(rng.next_float(), rng.next_float()));
        double x = 0.0;
        if (ls.valid() && (!restrict || through(ls.wi)))
          x = luminance(ls.radiance) * std::max(0.0f, ls.wi.y) / ls.pdf;
        if (!restrict) {
          EXPECT_TRUE(!ls.valid() || through(ls.wi));
        }
        sum += x;
        sum2 += x * x;
      }
      const double mean = sum / kN;
      *variance = sum2 / kN - mean * mean;
      return std::pair(mean, std::sqrt(*variance / kN));
    };
    double var_portal = 0, var_map = 0;
    const auto [portal_mean, portal_se] = estimate(env, false, &var_portal);
    const auto [map_mean, map_se] = estimate(map, true, &var_map);
    EXPECT_NEAR(portal_mean, expected, 4.0 * portal_se + 2e-3 * expected) << windows << " window(s)";
    EXPECT_NEAR(map_mean, expected, 4.0 * map_se + 2e-3 * expected) << windows << " window(s)";
    EXPECT_LT(var_portal * 10.0, var_map) << windows << " window(s)";
  }
}

// Where no portal is seen (the environment's side), sample, pdf and eval_pdf are the map's; from inside, eval_pdf
// is eval's radiance and pdf's density, and a sample's density is pdf()'s at its direction.
TEST(EnvironmentPortal, LightKeepsTheMapOutsideAndAgreesInside) {
  const int w = 64, h = 32;
  const EnvironmentLight map(map_with_sun(w, h), w, h, 1.0f, 0.0f);
  EnvironmentLight env(map_with_sun(w, h), w, h, 1.0f, 0.0f);
  env.set_portals({kWindowX, kWindowZ});
  Pcg32 rng(7);
  const LightSampleContext outside{Vec3(4.0f, 1.0f, 3.0f), Vec3(0.0f)};
  const LightSampleContext inside{Vec3(0.0f, 1.0f, 0.0f), Vec3(0.0f)};
  for (int i = 0; i < 2000; ++i) {
    const Vec2 u(rng.next_float(), rng.next_float());
    const LightSample a = map.sample(outside, u), b = env.sample(outside, u);
    ASSERT_EQ(a.wi, b.wi);
    ASSERT_EQ(a.pdf, b.pdf);
    ASSERT_EQ(map.pdf(outside, LightHit{a.wi}), env.pdf(outside, LightHit{a.wi}));
    const LightSample s = env.sample(inside, u);
    ASSERT_TRUE(s.valid());
    float p = -1.0f;
    const Rgb L = env.eval_pdf(inside, LightHit{s.wi}, &p);
    ASSERT_EQ(L, env.eval(LightHit{s.wi}));
    ASSERT_EQ(L, s.radiance);
    ASSERT_EQ(p, env.pdf(inside, LightHit{s.wi}));
    EXPECT_NEAR(p / s.pdf, 1.0f, 1e-5f);
  }
  // A direction that misses both windows has density 0 from inside: a BSDF ray leaving by another opening keeps its
  // whole MIS weight.
  EXPECT_EQ(env.pdf(inside, LightHit{Vec3(0, 1, 0)}), 0.0f);
}

std::string portal_scene(const std::string& portals) {
  return fmt::format(R"({{
    "camera": {{"position": [0, 1, 0], "look_at": [-1, 1, 0], "fov": 60, "resolution": [4, 4]}},
    "materials": {{"m": {{"type": "diffuse", "albedo": 0.5}}}},
    "shapes": [{{"type": "quad", "material": "m", "vertices": [[-2, 0, -2], [-2, 0, 2], [-2, 2, 2], [-2, 2, -2]]}}],
    "lights": [{{"type": "environment", "radiance": 1, "portals": {}}}] }})",
                     portals);
}

std::string load_error(const std::string& portals) {
  try {
    render_json(portal_scene(portals), 1);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(EnvironmentPortal, SceneKeyErrorsNameThePath) {
  EXPECT_NE(load_error(R"([{"vertices": [[3, 0, 0], [3, 0, 1], [3, 1, 1]]}])").find("/lights/0/portals/0/vertices"),
            std::string::npos);
  const std::string skew = load_error(R"([{"vertices": [[3, 0, 0], [3, 0, 1], [3, 1, 1.5], [3, 1, 0]]}])");
  EXPECT_NE(skew.find("/lights/0/portals/0/vertices"), std::string::npos) << skew;
  EXPECT_NE(skew.find("rectangle"), std::string::npos) << skew;
  EXPECT_NE(load_error(R"([{"vertices": [[3, 0, 0], [3, 0, 0], [3, 1, 0], [3, 1, 0]]}])").find("area"),
            std::string::npos);
  EXPECT_NE(load_error(R"([{"vertices": [[3, 0, 0], [3, 0, 1], [3, 1, 1], [3, 1, 0]], "size": 2}])").find("size"),
            std::string::npos);
  std::string many = "[";
  for (int i = 0; i < 17; ++i) many += std::string(i ? ", " : "") + R"({"vertices": [[3, 0, 0], [3, 0, 1], [3, 1, 1], [3, 1, 0]]})";
  EXPECT_NE(load_error(many + "]").find("at most 16"), std::string::npos);
  EXPECT_EQ(load_error(R"([{"vertices": [[3, 0, 0], [3, 0, 1], [3, 1, 1], [3, 1, 0]]}])"), "");
}

// A closed room, 2 x 2 x 2, lit through a 0.8 x 0.6 window in its +x wall by a sky with a sun that falls through
// the window onto the floor; three bounces. With the window as a portal the image's mean is the same (within the
// two renders' noise) and its noise is lower.
std::string room(bool portal, const std::string& sky_file) {
  const char* window = R"([[1, 0.8, -0.4], [1, 0.8, 0.4], [1, 1.4, 0.4], [1, 1.4, -0.4]])";
  return fmt::format(R"({{
    "camera": {{"position": [0.9, 1.2, 0.9], "look_at": [-1, 0.6, -0.3], "fov": 70, "resolution": [24, 24]}},
    "render": {{"max_depth": 3, "filter": "box"}},
    "materials": {{"m": {{"type": "diffuse", "albedo": 0.6}}}},
    "shapes": [
      {{"type": "quad", "material": "m", "vertices": [[-1, 0, -1], [-1, 0, 1], [1, 0, 1], [1, 0, -1]]}},
      {{"type": "quad", "material": "m", "vertices": [[-1, 2, -1], [1, 2, -1], [1, 2, 1], [-1, 2, 1]]}},
      {{"type": "quad", "material": "m", "vertices": [[-1, 0, -1], [1, 0, -1], [1, 2, -1], [-1, 2, -1]]}},
      {{"type": "quad", "material": "m", "vertices": [[-1, 0, 1], [-1, 2, 1], [1, 2, 1], [1, 0, 1]]}},
      {{"type": "quad", "material": "m", "vertices": [[-1, 0, -1], [-1, 2, -1], [-1, 2, 1], [-1, 0, 1]]}},
      {{"type": "quad", "material": "m", "vertices": [[1, 0, -1], [1, 0, 1], [1, 0.8, 1], [1, 0.8, -1]]}},
      {{"type": "quad", "material": "m", "vertices": [[1, 1.4, -1], [1, 1.4, 1], [1, 2, 1], [1, 2, -1]]}},
      {{"type": "quad", "material": "m", "vertices": [[1, 0.8, -1], [1, 0.8, -0.4], [1, 1.4, -0.4], [1, 1.4, -1]]}},
      {{"type": "quad", "material": "m", "vertices": [[1, 0.8, 0.4], [1, 0.8, 1], [1, 1.4, 1], [1, 1.4, 0.4]]}}],
    "lights": [{{"type": "environment", "file": "{}"{}}}] }})",
                     sky_file, portal ? fmt::format(R"(, "portals": [{{"vertices": {}}}])", window) : "");
}

TEST(EnvironmentPortal, RoomThroughItsWindowSameMeanLessNoise) {
  TempDir dir;
  // 128 x 64: a blue-grey sky over a dark ground, and a sun of radiance 2000 about 3 degrees wide towards
  // (1, 0.6, 0.2), which shines through the window onto the floor.
  const Vec3 sun = glm::normalize(Vec3(1.0f, 0.6f, 0.2f));
  const int w = 128, h = 64;
  write_test_exr(dir.path() / "sky.exr", w, h, [&](int x, int y, int c) {
    const float theta = kPi * (y + 0.5f) / h, phi = kTwoPi * ((x + 0.5f) / w - 0.5f);
    const Vec3 d(std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi));
    const float base = d.y > 0 ? (c == 2 ? 1.0f : 0.6f) : 0.1f;
    return base + 2000.0f * std::exp(-glm::dot(d - sun, d - sun) / (2 * 0.025f * 0.025f));
  });
  const auto render = [&](bool portal, uint64_t seed) {
    return image_stats(render_json(room(portal, (dir.path() / "sky.exr").string()), 64, 0, seed).film);
  };
  const ImageStats with = render(true, 1), without = render(false, 2);
  for (int c = 0; c < 3; ++c) {
    const double se = std::hypot(with.standard_error[c], without.standard_error[c]);
    EXPECT_NEAR(with.mean[c], without.mean[c], 4.0 * se) << "channel " << c;
    EXPECT_LT(with.standard_error[c] * 1.5f, without.standard_error[c]) << "channel " << c;
  }
}

}  // namespace
}  // namespace kozu::test
