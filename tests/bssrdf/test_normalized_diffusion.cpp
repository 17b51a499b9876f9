// The normalized-diffusion profile (bssrdf/normalized_diffusion.h): its cdf against numerical
// integration of R(r) 2πr, its total against the surface albedo for every parameterization, the exact
// inversion of the cdf (closed form and Newton), and a chi-square test of the radius sampling against
// R(r) 2πr integrated over each bin.
#include "bssrdf/normalized_diffusion.h"
#include "bssrdf/probe_sampling.h"
#include "core/math.h"
#include "core/rng.h"
#include "support/chi2.h"

#include <gtest/gtest.h>

#include <cmath>

namespace kozu {
namespace {

// ∫_a^b f by Gauss–Legendre on `segments` equal pieces.
template <class F>
double integrate(const F& f, double a, double b, int segments = 64) {
  static const test::GaussRule rule = test::gauss_legendre(16);
  double sum = 0.0;
  const double h = (b - a) / segments;
  for (int s = 0; s < segments; ++s) {
    const double lo = a + s * h;
    for (size_t k = 0; k < rule.x.size(); ++k) sum += 0.5 * h * rule.w[k] * f(lo + 0.5 * h * (rule.x[k] + 1.0));
  }
  return sum;
}

// R(r) 2πr from eval alone (not from pdf), so the tests below check eval, pdf and cdf against each other.
double energy_density(const NormalizedDiffusion& p, double r) { return p.eval(static_cast<float>(r)) * kTwoPi * r; }

constexpr SubsurfaceParameterization kParams[] = {SubsurfaceParameterization::Searchlight,
                                                   SubsurfaceParameterization::Diffuse,
                                                   SubsurfaceParameterization::Dmfp};

TEST(NormalizedDiffusion, CdfMatchesIntegratedProfile) {
  for (float d : {0.05f, 1.0f, 7.0f}) {
    const NormalizedDiffusion p(0.7f, d);
    for (double x : {0.01, 0.1, 0.5, 1.0, 3.0, 10.0, 30.0}) {
      const double r = x * d;
      const double integral = integrate([&](double t) { return energy_density(p, t); }, 0.0, r) / 0.7;
      EXPECT_NEAR(p.cdf(r), integral, 2e-6) << "d " << d << " r " << r;
      // pdf is the derivative of the cdf
      const double h = 1e-4 * r;
      EXPECT_NEAR(p.pdf(static_cast<float>(r)), (p.cdf(r + h) - p.cdf(r - h)) / (2 * h), 1e-4 * p.pdf(float(r)));
    }
  }
}

// ∫ R(r) 2πr dr = A to 1e-4 for all three parameterizations and the whole range of A.
TEST(NormalizedDiffusion, ProfileIntegratesToAlbedo) {
  for (SubsurfaceParameterization pz : kParams) {
    for (float A : {0.01f, 0.1f, 0.33f, 0.5f, 0.8f, 0.95f, 1.0f}) {
      for (float length : {0.02f, 1.0f, 25.0f}) {
        const NormalizedDiffusion p = NormalizedDiffusion::from_length(pz, A, length);
        const double d = p.d();
        // The 1/r peak at 0 is integrable but cancels in R 2πr; the tail beyond 60 d holds e^{-20}.
        const double total = integrate([&](double r) { return energy_density(p, r); }, 0.0, 60.0 * d, 256);
        EXPECT_NEAR(total, A, 1e-4 * A) << "parameterization " << int(pz) << " A " << A << " length " << length;
        EXPECT_NEAR(d, length / normalized_diffusion::scale(pz, A), 1e-6 * d);
      }
    }
  }
}

TEST(NormalizedDiffusion, ScaleFormulas) {
  // The three fits at A = 0.8 and 0.33, where their shifted terms vanish (eqs. 5, 6, 8).
  EXPECT_DOUBLE_EQ(normalized_diffusion::scale(SubsurfaceParameterization::Searchlight, 0.8), 1.85 - 0.8);
  EXPECT_DOUBLE_EQ(normalized_diffusion::scale(SubsurfaceParameterization::Diffuse, 0.8), 1.9 - 0.8);
  EXPECT_DOUBLE_EQ(normalized_diffusion::scale(SubsurfaceParameterization::Dmfp, 0.33), 3.5);
  // and the odd/even shape of the correction terms
  EXPECT_NEAR(normalized_diffusion::scale(SubsurfaceParameterization::Searchlight, 0.3), 1.85 - 0.3 + 7 * 0.125, 1e-12);
  EXPECT_NEAR(normalized_diffusion::scale(SubsurfaceParameterization::Diffuse, 0.3), 1.9 - 0.3 + 3.5 * 0.25, 1e-12);
  EXPECT_NEAR(normalized_diffusion::scale(SubsurfaceParameterization::Dmfp, 0.83), 3.5 + 100 * 0.0625, 1e-12);
}

// Both inversions of eq. (11) return the radius whose cdf is u, to 1e-6, and agree with each other.
TEST(NormalizedDiffusion, SamplingInvertsTheCdf) {
  const NormalizedDiffusion p(0.6f, 0.37f);
  Pcg32 rng(11);
  double worst_closed = 0, worst_newton = 0, worst_pair = 0;
  int max_iterations = 0;
  for (int i = 0; i < 200000; ++i) {
    // Cover the ends: u near 0 (r → 0) and near 1 (the tail).
    const float u = i < 1000 ? std::ldexp(rng.next_float(), -(i % 24)) : rng.next_float();
    int iterations = 0;
    const float r1 = p.sample_closed_form(u), r2 = p.sample(u, &iterations);
    max_iterations = std::max(max_iterations, iterations);
    // The cdf's slope is at most 1/(2d): an error in u of e maps to at least 2d·e in r, so compare in u.
    worst_closed = std::max(worst_closed, std::abs(p.cdf(r1) - u));
    worst_newton = std::max(worst_newton, std::abs(p.cdf(r2) - u));
    worst_pair = std::max(worst_pair, double(std::abs(r1 - r2)) / std::max(double(r1), 1e-3 * p.d()));
  }
  // float r carries a relative rounding of 6e-8; the cdf's slope bounds its effect on u by that much.
  EXPECT_LT(worst_closed, 1e-6);
  EXPECT_LT(worst_newton, 1e-6);
  EXPECT_LT(worst_pair, 1e-6);
  EXPECT_LE(max_iterations, 8);
}

// Chi-square of the sampled radius against R(r) 2πr / A integrated over each bin (from eval, by
// quadrature). Bins: 60 equal cells on [0, 12 d), 20 wider ones to 40 d, and the tail as one cell.
TEST(NormalizedDiffusion, RadiusSamplingChi2) {
  const int n = 1'000'000;
  const int tests = 9;  // the family: three parameterizations times three albedos
  for (SubsurfaceParameterization pz : kParams) {
    for (float A : {0.05f, 0.5f, 0.95f}) {
      const NormalizedDiffusion p = NormalizedDiffusion::from_length(pz, A, 0.8f);
      std::vector<double> edges;
      for (int i = 0; i <= 60; ++i) edges.push_back(12.0 * p.d() * i / 60);
      for (int i = 1; i <= 20; ++i) edges.push_back(p.d() * (12.0 + 28.0 * i / 20));
      std::vector<double> observed(edges.size(), 0.0), expected(edges.size(), 0.0);
      Pcg32 rng(uint64_t(1000 * A) + 7 * int(pz));
      for (int i = 0; i < n; ++i) {
        const double r = p.sample(rng.next_float());
        const auto it = std::upper_bound(edges.begin(), edges.end(), r);
        observed[std::min<size_t>(it - edges.begin() - 1, edges.size() - 1)] += 1;
      }
      double inside = 0;
      for (size_t b = 0; b + 1 < edges.size(); ++b) {
        expected[b] = n * integrate([&](double r) { return energy_density(p, r) / A; }, edges[b], edges[b + 1], 2);
        inside += expected[b];
      }
      expected.back() = n - inside;  // the tail beyond 40 d
      test::Chi2Options opt;
      opt.test_count = tests;
      const test::Chi2Result res = test::chi2_test_counts(observed, expected, opt);
      EXPECT_TRUE(res.passed) << "parameterization " << int(pz) << " A " << A << ": " << res.message;
    }
  }
}

// The probe's truncated radius sampling (probe_sampling.h) against its truncated pdf.
TEST(RgbProfile, TruncatedRadiusSamplingChi2) {
  const RgbProfile prof({NormalizedDiffusion(0.9f, 0.1f), NormalizedDiffusion(0.5f, 0.3f), NormalizedDiffusion(0.2f, 1.0f)});
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(prof.channel(c).cdf(prof.r_max(c)), kProbeFraction, 1e-6);
    const double rmax = prof.r_max(c);
    test::Chi2Grid2D grid;
    grid.x0 = 0;
    grid.x1 = rmax;
    grid.x_bins = 100;
    grid.y_bins = 1;
    test::Chi2Options opt;
    opt.test_count = 3;
    opt.integration_points = 16;
    const test::Chi2Result res = test::chi2_test_2d(
        [&](const Vec2& u) -> std::optional<Vec2> { return Vec2(prof.sample_radius(c, u.x), 0.5f); },
        [&](const Vec2& q) { return double(prof.pdf_radius(c, q.x)); }, grid, opt);
    EXPECT_TRUE(res.passed) << "channel " << c << ": " << res.message;
  }
}

}  // namespace
}  // namespace kozu
