// The two distance samplers of homogeneous media, each against its own density by chi-square (tests/support/chi2.h):
//  - equiangular sampling towards a point (media/equiangular.h), over kEquiangularCases, and its density against the
//    closed form and its integral;
//  - free flights with spectral MIS (media/homogeneous_flight.h): grey, chromatic with an uneven throughput, and a
//    channel of σt 0 over an infinite segment; a flight past t_max counts as lost, so the lost cell checks
//    pass_probability() against 1 − ∫ pdf.
#include "media/equiangular.h"
#include "media/homogeneous_flight.h"
#include "support/chi2.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <optional>

namespace kozu {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// Chi-square of a distance sampler on [x0, x1) in `bins` cells: sample(u) is the distance from u.x (and u.y), nullopt
// for a sample past x1 (the lost cell, which expects the mass the density leaves outside).
test::Chi2Result chi2_distance(const std::function<std::optional<float>(const Vec2&)>& sample,
                               const std::function<float(float)>& pdf, float x0, float x1, int bins, int test_count) {
  test::Chi2Grid2D grid;
  grid.x0 = x0;
  grid.x1 = x1;
  grid.x_bins = bins;
  grid.y_bins = 1;
  test::Chi2Options opt;
  opt.test_count = test_count;
  opt.integration_points = 16;
  return test::chi2_test_2d(
      [&](const Vec2& u) -> std::optional<Vec2> {
        const std::optional<float> t = sample(u);
        return t ? std::optional<Vec2>(Vec2(*t, 0.5f)) : std::nullopt;
      },
      [&](const Vec2& p) { return double(pdf(p.x)); }, grid, opt);
}

struct EquiangularCase {
  const char* name;
  Vec3 o, d;
  float a, b;
  Vec3 c;
  float bin_end;  // the binned range is [a, bin_end)
};

// Segments and points for both equiangular tests: a peak inside, the point behind the origin, an infinite segment
// (the mass past the binned range is checked as the lost cell), one with the point far off the line ahead, a short
// far segment (a small angle) and a point near the line.
const EquiangularCase kEquiangularCases[] = {
    {"peak inside", Vec3(0.0f), Vec3(1, 0, 0), 0.0f, 4.0f, Vec3(1.5f, 0.3f, 0.0f), 4.0f},
    {"point behind the origin", Vec3(0.2f, -0.1f, 0.3f), glm::normalize(Vec3(1, 1, 0)), 0.5f, 3.0f,
     Vec3(-1.0f, 0.5f, 0.0f), 3.0f},
    {"infinite segment", Vec3(0.0f), Vec3(0, 0, -1), 0.0f, kInf, Vec3(0.2f, 0.0f, -1.0f), 20.0f},
    {"infinite, point ahead far off the line", Vec3(0.0f), Vec3(0, 1, 0), 0.0f, kInf, Vec3(50.0f, 3.0f, 0.0f), 300.0f},
    {"short far segment", Vec3(0.0f), Vec3(1, 0, 0), 100.0f, 100.5f, Vec3(0.0f, 2.0f, 0.0f), 100.5f},
    {"point near the line", Vec3(0.0f), Vec3(0, 1, 0), 0.0f, 2.0f, Vec3(0.0f, 1.0f, 0.02f), 2.0f},
};

TEST(Equiangular, SamplesItsDensity) {
  for (const auto& k : kEquiangularCases) {
    const Equiangular eq(k.o, k.d, k.a, k.b, k.c);
    ASSERT_TRUE(eq.valid()) << k.name;
    const test::Chi2Result r = chi2_distance(
        [&](const Vec2& u) -> std::optional<float> {
          const float t = eq.sample(u.x);
          if (!(t >= k.a && t < k.b)) return -1.0f;  // outside the segment: fails the test
          if (t >= k.bin_end) return std::nullopt;   // past the binned range: the lost cell
          return t;
        },
        [&](float t) { return eq.pdf(t); }, k.a, k.bin_end, 200, 4);
    EXPECT_TRUE(r.passed) << k.name << ": " << r.message;
  }
}

// The density against its closed form with θ_b − θ_a as the difference of two arctangents (Kulla & Fajardo 2012
// eq. 5, in double), and its integral over [a, b) by the midpoint rule in θ (t = Δ + D tan θ), which equiangular.cpp
// does not use: its single atan2 of the two end vectors must be that difference, a short far segment included (a
// small angle, where the difference of two arctangents loses digits).
TEST(Equiangular, DensityIsTheClosedFormAndIntegratesToOne) {
  for (const auto& k : kEquiangularCases) {
    const Equiangular eq(k.o, k.d, k.a, k.b, k.c);
    ASSERT_TRUE(eq.valid()) << k.name;
    const glm::dvec3 oc = glm::dvec3(k.c) - glm::dvec3(k.o);
    const double delta = glm::dot(oc, glm::dvec3(k.d));
    const double dist = glm::length(oc - delta * glm::dvec3(k.d));
    const double th_a = std::atan((double(k.a) - delta) / dist);
    const double th_b = std::isinf(k.b) ? 0.5 * 3.14159265358979323846 : std::atan((double(k.b) - delta) / dist);
    const int n = 200000;
    double integral = 0.0, worst = 0.0;
    for (int i = 0; i < n; ++i) {
      const double th = th_a + (i + 0.5) / n * (th_b - th_a);
      const double t = delta + dist * std::tan(th);
      const float tf = static_cast<float>(t);
      if (!(tf >= k.a && tf < k.b)) continue;  // rounded onto b: outside
      const double expected = dist / ((th_b - th_a) * (dist * dist + (t - delta) * (t - delta)));
      const double pdf = eq.pdf(tf);
      if (t < 1e6) worst = std::max(worst, std::abs(pdf / expected - 1.0));
      // dt = D (1 + tan² θ) dθ, evaluated at t itself (the float t the pdf was asked about differs by rounding).
      integral += pdf * dist * (1.0 + std::tan(th) * std::tan(th)) *
                  (th_b - th_a) / n;
    }
    EXPECT_LT(worst, 1e-4) << k.name;
    EXPECT_NEAR(integral, 1.0, 1e-3) << k.name;
  }
}

TEST(Equiangular, PointOnTheLineIsNotSampled) {
  // A spike floats cannot hold: the caller falls back to free flights alone.
  EXPECT_FALSE(Equiangular(Vec3(0.0f), Vec3(1, 0, 0), 0.0f, 5.0f, Vec3(2.0f, 0.0f, 0.0f)).valid());
  EXPECT_FALSE(Equiangular(Vec3(0.0f), Vec3(1, 0, 0), 1.0f, 1.0f, Vec3(2.0f, 1.0f, 0.0f)).valid());  // empty
  EXPECT_EQ(Equiangular(Vec3(0.0f), Vec3(1, 0, 0), 0.0f, 5.0f, Vec3(2.0f, 1.0f, 0.0f)).pdf(5.0f), 0.0f);
}

struct FlightCase {
  const char* name;
  Rgb sigma_t, beta;
  float t_max, bin_end;
};

TEST(HomogeneousFlight, SamplesItsDensity) {
  const FlightCase cases[] = {
      {"grey", Rgb(2.0f), Rgb(1.0f), 1.5f, 1.5f},
      {"chromatic, uneven throughput", Rgb(0.5f, 2.0f, 6.0f), Rgb(1.0f, 0.3f, 0.05f), 3.0f, 3.0f},
      {"a clear channel, infinite segment", Rgb(0.0f, 1.0f, 3.0f), Rgb(1.0f), kInf, 12.0f},
  };
  for (const auto& k : cases) {
    const HomogeneousFlight flight(k.sigma_t, k.beta);
    const test::Chi2Result r = chi2_distance(
        [&](const Vec2& u) -> std::optional<float> {
          const float t = flight.sample(u.x, u.y);
          if (t >= k.bin_end) return std::nullopt;  // passed t_max (or past the binned range)
          return t;
        },
        [&](float t) { return flight.pdf(t); }, 0.0f, k.bin_end, 150, 3);
    EXPECT_TRUE(r.passed) << k.name << ": " << r.message;
    if (std::isfinite(k.t_max))
      EXPECT_NEAR(flight.pass_probability(k.t_max), 1.0 - r.pdf_integral, 1e-4) << k.name;
    else
      EXPECT_NEAR(flight.pass_probability(k.t_max), 1.0 / 3.0, 1e-6) << k.name;  // the clear channel's share
  }
}

TEST(HomogeneousFlight, TransmittanceOfAClearChannelIsOne) {
  const Rgb T = homogeneous_transmittance(Rgb(0.0f, 1.0f, 2.0f), kInf);
  EXPECT_EQ(T, Rgb(1.0f, 0.0f, 0.0f));
  EXPECT_FLOAT_EQ(homogeneous_transmittance(Rgb(2.0f), 0.5f).g, std::exp(-1.0f));
}

}  // namespace
}  // namespace kozu
