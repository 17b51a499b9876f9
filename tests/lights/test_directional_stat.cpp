// The directional light with an angular diameter (lights/directional.h): chi-square of its cone sampling
// against its own pdf, the pdf's integral over the sphere, and Monte Carlo irradiance against the closed form
// E cos(alpha) with light sampling, cosine (BSDF-like) sampling and their MIS combination.
#include "support/chi2.h"

#include "core/frame.h"
#include "core/rng.h"
#include "core/warp.h"
#include "lights/directional.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <vector>

namespace kozu::test {
namespace {

// The chi-square family of this file: 4 diameters in cone coordinates plus 2 on the sphere.
constexpr int kChi2Tests = 6;
// Monte Carlo comparisons allow z standard errors (estimated from the samples) plus float round-off.
constexpr double kZ = 5.0;
constexpr double kRoundOff = 1e-5;

const Vec3 kDirection(0.3f, -1.0f, 0.45f);  // where the light travels; tilted off every axis

// 1 - cos(theta_max) in double, from the diameter in degrees, independently of the light.
double one_minus_cos_max(double diameter_deg) {
  const double half = 0.5 * diameter_deg * M_PI / 180.0;
  return 2.0 * std::pow(std::sin(0.5 * half), 2.0);
}

// An orthonormal frame (double) around the unit vector towards the light, for the test's own coordinates.
struct ConeFrame {
  Vec3d s, t, n;
  explicit ConeFrame(const Vec3& travel_direction) {
    n = -glm::normalize(Vec3d(travel_direction));
    orthonormal_basis(n, s, t);
  }
  // The direction at 1 - cos(theta) = omc and azimuth phi.
  Vec3 direction(double omc, double phi) const {
    const double sin_t = std::sqrt(std::max(0.0, omc * (2.0 - omc)));
    return Vec3(s * (sin_t * std::cos(phi)) + t * (sin_t * std::sin(phi)) + n * (1.0 - omc));
  }
  // (1 - cos theta, phi) of a unit direction; 1 - cos theta = |w - n|^2 / 2 keeps small angles exact.
  glm::dvec2 coords(const Vec3& w) const {
    const Vec3d d = Vec3d(w) - n;
    double phi = std::atan2(glm::dot(Vec3d(w), t), glm::dot(Vec3d(w), s));
    if (phi < 0.0) phi += 2.0 * M_PI;
    return glm::dvec2(0.5 * glm::dot(d, d), phi);
  }
};

class DirectionalCone : public ::testing::TestWithParam<float> {};

// Samples mapped to (s, t) = ((1 - cos theta) / (1 - cos theta_max), phi / 2 pi) in [0, 1)^2, where the claimed
// density is pdf(w) * 2 pi (1 - cos theta_max): uniform cells however narrow the cone, which binning in
// world cos(theta) cannot resolve for the sun (its cone spans 1e-5 in cos theta, near float's resolution).
TEST_P(DirectionalCone, Chi2InConeCoordinates) {
  const float diameter = GetParam();
  const DirectionalLight light(kDirection, Rgb(1.0f), diameter);
  const ConeFrame f(kDirection);
  const double omc_max = one_minus_cos_max(diameter);
  // A sample on the rim may land past s = 1 by the rounding of a float direction: |w - n| carries ~1e-7
  // absolute error, so s by 2e-7 / sqrt(omc_max) relative (2e-5 for the sun); larger overshoots fail.
  const double rim_slack = 4e-7 / std::sqrt(omc_max) + 1e-6;
  const LightSampleContext ctx{Vec3(0.0f), Vec3(0.0f)};
  Chi2Options opt;
  opt.test_count = kChi2Tests;
  const Chi2Result r = chi2_test_2d(
      [&](const Vec2& u) -> std::optional<Vec2> {
        const LightSample ls = light.sample(ctx, u);
        if (!ls.valid()) return std::nullopt;
        const glm::dvec2 c = f.coords(ls.wi);
        const double s = c.x / omc_max;
        const float t = std::min(static_cast<float>(c.y / (2.0 * M_PI)), kOneMinusEpsilon);
        if (s >= 1.0 + rim_slack) return Vec2(static_cast<float>(s), t);  // outside the grid: fails
        return Vec2(std::min(static_cast<float>(s), kOneMinusEpsilon), t);
      },
      [&](const Vec2& st) -> double {
        const Vec3 w = f.direction(st.x * omc_max, st.y * 2.0 * M_PI);
        return light.pdf(ctx, LightHit{w}) * 2.0 * M_PI * omc_max;
      },
      Chi2Grid2D{}, opt);
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_integral, 1.0, 1e-4);
}

// The pdf over the whole sphere, by Gauss-Legendre quadrature in (1 - cos theta, phi) about the axis, split at
// the cone's edge so that the discontinuity lies on a cell boundary (the quadrature is then exact up to
// round-off).
TEST_P(DirectionalCone, PdfIntegratesToOne) {
  const float diameter = GetParam();
  const DirectionalLight light(kDirection, Rgb(1.0f), diameter);
  const ConeFrame f(kDirection);
  const double omc_max = one_minus_cos_max(diameter);
  const LightSampleContext ctx{Vec3(0.0f), Vec3(0.0f)};
  const GaussRule g = gauss_legendre(8);
  const int phi_cells = 64, omc_cells = 16;
  double integral = 0.0;
  for (const auto& [lo, hi] : {std::pair{0.0, omc_max}, std::pair{omc_max, 2.0}}) {
    if (!(hi > lo)) continue;
    for (int i = 0; i < omc_cells; ++i) {
      const double a = lo + (hi - lo) * i / omc_cells, b = lo + (hi - lo) * (i + 1) / omc_cells;
      for (int j = 0; j < phi_cells; ++j) {
        const double c = 2.0 * M_PI * j / phi_cells, d = 2.0 * M_PI * (j + 1) / phi_cells;
        for (size_t k = 0; k < g.x.size(); ++k)
          for (size_t l = 0; l < g.x.size(); ++l) {
            const double omc = 0.5 * (a + b) + 0.5 * (b - a) * g.x[k];
            const double phi = 0.5 * (c + d) + 0.5 * (d - c) * g.x[l];
            // d omega = d(cos theta) d phi = d(omc) d phi
            integral += g.w[k] * g.w[l] * 0.25 * (b - a) * (d - c) * light.pdf(ctx, LightHit{f.direction(omc, phi)});
          }
      }
    }
  }
  EXPECT_NEAR(integral, 1.0, kRoundOff) << "angular diameter " << diameter;
}

// Irradiance on a plane whose normal makes angle alpha with the direction towards the light, with the whole
// cone above the plane: E_plane = integral of L (n . w) over the cone = L (n . axis) pi sin^2 theta_max
// = E cos(alpha) (the cone's mean direction is along its axis). Estimated three ways, each of which must agree:
//   light   sample the light, L (n . w) / pdf
//   bsdf    cosine-weighted directions around n (a Lambertian BSDF's sampling), L (n . w) / (cos / pi) = pi L
//   mis     one sample of each, power heuristic with the other's pdf (as integrators/path.cpp combines them)
struct Estimate {
  Rgb mean{0.0f};
  Rgb standard_error{0.0f};
};

template <class F>
Estimate monte_carlo(int n, uint64_t seed, F&& sample) {
  Pcg32 rng(seed);
  Vec3d sum(0.0), sum2(0.0);
  for (int i = 0; i < n; ++i) {
    const Vec3d x(sample(rng));
    sum += x;
    sum2 += x * x;
  }
  const Vec3d mean = sum / double(n);
  const Vec3d var = glm::max(sum2 / double(n) - mean * mean, Vec3d(0.0)) / double(n - 1);
  return {Rgb(mean), Rgb(glm::sqrt(var))};
}

void expect_estimate(const Estimate& e, const Rgb& expected, const std::string& what) {
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(e.mean[c], expected[c], kZ * e.standard_error[c] + kRoundOff * expected[c])
        << what << " channel " << c << " (standard error " << e.standard_error[c] << ")";
}

struct IrradianceCase {
  float diameter;
  float alpha_deg;  // angle between the plane's normal and the direction towards the light
  bool bsdf;        // whether cosine sampling alone finds the cone often enough to be compared
};

void PrintTo(const IrradianceCase& c, std::ostream* os) {
  *os << "diameter " << c.diameter << ", alpha " << c.alpha_deg;
}

class DirectionalIrradiance : public ::testing::TestWithParam<IrradianceCase> {};

TEST_P(DirectionalIrradiance, MatchesClosedForm) {
  const IrradianceCase c = GetParam();
  const Rgb E(1000.0f, 800.0f, 550.0f);
  const DirectionalLight light(kDirection, E, c.diameter);
  const ConeFrame f(kDirection);
  // The plane's normal: the axis turned by alpha about the frame's s vector.
  const double alpha = c.alpha_deg * M_PI / 180.0;
  const Vec3 n(f.n * std::cos(alpha) + f.t * std::sin(alpha));
  const LightSampleContext ctx{Vec3(0.0f), n};
  const Rgb expected = E * static_cast<float>(std::cos(alpha));
  const Frame shading(n);
  const std::string what = fmt::format("diameter {}, alpha {}", c.diameter, c.alpha_deg);
  constexpr int kN = 400'000;

  auto light_sample = [&](Pcg32& rng, float* weight_out) {
    const LightSample ls = light.sample(ctx, Vec2(rng.next_float(), rng.next_float()));
    if (!ls.valid()) return Rgb(0.0f);
    const float cos_n = std::max(0.0f, glm::dot(n, ls.wi));
    const float bsdf_pdf = cos_n * kInvPi;
    *weight_out = light.is_delta() ? 1.0f : power_heuristic(ls.pdf, bsdf_pdf);
    return ls.radiance * (cos_n / ls.pdf);
  };
  auto bsdf_sample = [&](Pcg32& rng, float* weight_out) {
    const Vec3 local = warp::square_to_cosine_hemisphere(Vec2(rng.next_float(), rng.next_float()));
    if (!(local.z > 0.0f)) return Rgb(0.0f);
    const Vec3 w = shading.to_world(local);
    const Rgb L = light.eval(LightHit{w});
    *weight_out = power_heuristic(local.z * kInvPi, light.pdf(ctx, LightHit{w}));
    return L * kPi;  // L cos / (cos / pi)
  };

  float w;
  expect_estimate(monte_carlo(kN, 11, [&](Pcg32& rng) { return light_sample(rng, &w); }), expected,
                  what + ", light sampling");
  expect_estimate(monte_carlo(kN, 12,
                              [&](Pcg32& rng) {
                                float wl = 0.0f, wb = 0.0f;
                                const Rgb a = light_sample(rng, &wl);
                                const Rgb b = bsdf_sample(rng, &wb);
                                return a * wl + b * wb;
                              }),
                  expected, what + ", MIS");
  if (c.bsdf)
    expect_estimate(monte_carlo(kN, 13, [&](Pcg32& rng) { return bsdf_sample(rng, &w); }), expected,
                    what + ", cosine sampling");
}

INSTANTIATE_TEST_SUITE_P(Diameters, DirectionalCone, ::testing::Values(0.53f, 5.0f, 40.0f, 180.0f),
                         [](const auto& p) { return fmt::format("d{}", static_cast<int>(p.param * 100)); });

INSTANTIATE_TEST_SUITE_P(Planes, DirectionalIrradiance,
                         ::testing::Values(IrradianceCase{0.0f, 0.0f, false}, IrradianceCase{0.0f, 60.0f, false},
                                           IrradianceCase{0.53f, 0.0f, false}, IrradianceCase{0.53f, 60.0f, false},
                                           IrradianceCase{5.0f, 30.0f, true}, IrradianceCase{40.0f, 0.0f, true},
                                           IrradianceCase{40.0f, 65.0f, true}, IrradianceCase{120.0f, 25.0f, true},
                                           IrradianceCase{180.0f, 0.0f, true}),
                         [](const auto& p) {
                           return fmt::format("d{}_alpha{}", static_cast<int>(p.param.diameter * 100),
                                              static_cast<int>(p.param.alpha_deg));
                         });

// Binned on the sphere in world coordinates, with the axis on +z so that the cone's edge is a cell boundary.
TEST(DirectionalChi2, WideConesOnTheSphere) {
  for (const float diameter : {40.0f, 180.0f}) {
    const DirectionalLight light(Vec3(0.0f, 0.0f, -2.0f), Rgb(1.0f), diameter);
    const LightSampleContext ctx{Vec3(0.0f), Vec3(0.0f)};
    Chi2Options opt;
    opt.test_count = kChi2Tests;
    // The cell edge 1e-6 below the cone's edge: samples on the rim may round below cos(theta_max) by ~1e-7, and
    // the sliver this adds to the last ring of cells changes their expected counts by < 1e-3 relative.
    opt.cos_theta_min = std::cos(0.5 * diameter * M_PI / 180.0) - 1e-6;
    opt.check_lost_mass = false;  // the sliver is not integrated to 1e-5; PdfIntegratesToOne checks the mass
    const Chi2Result r = chi2_test(
        [&](const Vec2& u) -> std::optional<Vec3> {
          const LightSample ls = light.sample(ctx, u);
          if (!ls.valid()) return std::nullopt;
          return ls.wi;
        },
        [&](const Vec3& w) { return static_cast<double>(light.pdf(ctx, LightHit{w})); }, opt);
    EXPECT_TRUE(r.passed) << "diameter " << diameter << ": " << r.message;
    EXPECT_NEAR(r.pdf_integral, 1.0, 1e-4) << diameter;
  }
}

}  // namespace
}  // namespace kozu::test
