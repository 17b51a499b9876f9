// Tests of the sampling building blocks: every warp in core/warp.h (chi-square of sample against pdf,
// invert round trips, pdf normalisation), the discrete and piecewise-constant distributions of
// core/distribution.h, and the stratification of the Sobol sampler in core/sampler.h.
#include "core/distribution.h"
#include "core/rng.h"
#include "core/sampler.h"
#include "core/warp.h"
#include "support/chi2.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstring>
#include <numbers>
#include <numeric>
#include <set>
#include <vector>

namespace kozu::test {
namespace {

constexpr double kPiD = std::numbers::pi;

// Šidák family: the chi-square tests in this file (6 direction warps, 2 Marsaglia warps, disk, triangle, tent,
// Distribution1D, Distribution2D, AliasTable).
constexpr int kChi2Tests = 14;

Chi2Options chi2_options(uint64_t seed) {
  Chi2Options options;
  options.test_count = kChi2Tests;
  options.seed = seed;
  return options;
}

// Every value Pcg32::next_float and the Sampler can return: k * 2^-24 for k < 2^24.
constexpr uint32_t kUnitFloatCount = 1U << 24;
float unit_float(uint32_t k) { return static_cast<float>(k) * 0x1p-24f; }

// Midpoints of an n x n grid on the unit square.
std::vector<Vec2> midpoint_grid(int n) {
  std::vector<Vec2> grid;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) grid.emplace_back((i + 0.5f) / n, (j + 0.5f) / n);
  return grid;
}

// ---------------------------------------------------------------------------------------------------------
// Direction warps: one row per warp (a new warp is one new row).

struct DirectionWarp {
  std::string name;
  double cos_theta_min;  // support: cos(theta) >= cos_theta_min (the chi-square bins cover exactly this)
  uint64_t seed;
  std::function<Vec3(const Vec2&)> sample;
  std::function<float(const Vec3&)> pdf;
  std::function<Vec2(const Vec3&)> invert;
};

DirectionWarp cone(const std::string& name, float cos_max, uint64_t seed) {
  return {name,
          cos_max,
          seed,
          [cos_max](const Vec2& u) { return warp::square_to_uniform_cone(u, cos_max); },
          [cos_max](const Vec3& w) { return warp::square_to_uniform_cone_pdf(w, cos_max); },
          [cos_max](const Vec3& w) { return warp::uniform_cone_to_square(w, cos_max); }};
}

std::vector<DirectionWarp> direction_warps() {
  return {
      {"UniformSphere", -1.0, 11, warp::square_to_uniform_sphere, warp::square_to_uniform_sphere_pdf,
       warp::uniform_sphere_to_square},
      {"UniformHemisphere", 0.0, 12, warp::square_to_uniform_hemisphere, warp::square_to_uniform_hemisphere_pdf,
       warp::uniform_hemisphere_to_square},
      {"CosineHemisphere", 0.0, 13, warp::square_to_cosine_hemisphere, warp::square_to_cosine_hemisphere_pdf,
       warp::cosine_hemisphere_to_square},
      cone("UniformCone099", 0.99f, 14),
      cone("UniformCone05", 0.5f, 15),
      cone("UniformConeMinus03", -0.3f, 16),
  };
}

void PrintTo(const DirectionWarp& w, std::ostream* os) { *os << w.name; }

class DirectionWarpTest : public testing::TestWithParam<DirectionWarp> {};

INSTANTIATE_TEST_SUITE_P(Warp, DirectionWarpTest, testing::ValuesIn(direction_warps()),
                         [](const testing::TestParamInfo<DirectionWarp>& row) { return row.param.name; });

TEST_P(DirectionWarpTest, Chi2) {
  const DirectionWarp& w = GetParam();
  // Bins on the support only, so even the 0.99 cone gets 40 x 80 cells; the rest of the sphere is one cell
  // that expects nothing, so a single sample outside the support fails the test.
  Chi2Options options = chi2_options(w.seed);
  options.cos_theta_min = w.cos_theta_min;
  const Chi2Result r = chi2_test([&](const Vec2& u) { return std::optional(w.sample(u)); },
                                 [&](const Vec3& d) { return static_cast<double>(w.pdf(d)); }, options);
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_EQ(r.lost_samples, 0);
}

TEST_P(DirectionWarpTest, PdfIntegratesToOne) {
  // 200 cells in cos(theta) put cell edges on every multiple of 0.01, hence on each support boundary
  // (0, 0.99, 0.5, -0.3): the constant pieces are then integrated exactly and only rounding remains.
  const DirectionWarp& w = GetParam();
  EXPECT_NEAR(integrate_pdf_over_sphere([&](const Vec3& d) { return static_cast<double>(w.pdf(d)); }, 200), 1.0, 1e-3);
}

TEST_P(DirectionWarpTest, InvertRoundTrips) {
  // Interior grid points avoid the poles, where phi (and so u.y) is undefined. 1e-4 is ~1000 float ulps:
  // generous for rounding, far below any formula error.
  const DirectionWarp& w = GetParam();
  double worst = 0;
  Vec2 worst_u(0);
  for (const Vec2& u : midpoint_grid(64)) {
    const Vec2 v = w.invert(w.sample(u));
    const double error = std::max(std::abs(v.x - u.x), std::abs(v.y - u.y));
    if (error > worst) {
      worst = error;
      worst_u = u;
    }
  }
  EXPECT_LT(worst, 1e-4) << "worst at u = (" << worst_u.x << ", " << worst_u.y << ")";
}

TEST_P(DirectionWarpTest, SampleOfInverseIsIdentityOnTheEdges) {
  // On the edges of the square (poles, seams) u itself need not come back, but the direction must. 1e-3:
  // at the horizon, the cosine warp's z = sqrt(1 - r^2) turns one float ulp of r^2 into ~3.5e-4.
  const DirectionWarp& w = GetParam();
  double worst = 0;
  for (int i = 0; i <= 64; ++i) {
    const float t = std::min(i / 64.0f, kOneMinusEpsilon);
    for (const Vec2& u : {Vec2(t, 0), Vec2(0, t), Vec2(t, kOneMinusEpsilon), Vec2(kOneMinusEpsilon, t)}) {
      const Vec3 d = w.sample(u);
      worst = std::max(worst, static_cast<double>(glm::length(w.sample(w.invert(d)) - d)));
    }
  }
  EXPECT_LT(worst, 1e-3);
}

// ---------------------------------------------------------------------------------------------------------
// Marsaglia's rejection warps draw a variable number of random numbers from a generator, not a point u. They
// are driven by a generator that counts its draws, so the cost of the rejection loop can be tested too.

struct CountingRng {
  explicit CountingRng(uint64_t seed) : rng(seed) {}
  float next_float() {
    ++draws;
    return rng.next_float();
  }
  Pcg32 rng;
  int64_t draws = 0;
};

struct RejectionWarp {
  std::string name;
  double cos_theta_min;  // support, as for DirectionWarp
  uint64_t seed;
  std::function<Vec3(CountingRng&)> sample;
  std::function<float(const Vec3&)> pdf;
};

std::vector<RejectionWarp> rejection_warps() {
  return {
      {"MarsagliaSphere", -1.0, 41, warp::sample_sphere_marsaglia<CountingRng>, warp::sample_sphere_marsaglia_pdf},
      {"MarsagliaHemisphere", 0.0, 42, warp::sample_hemisphere_marsaglia<CountingRng>,
       warp::sample_hemisphere_marsaglia_pdf},
  };
}

void PrintTo(const RejectionWarp& w, std::ostream* os) { *os << w.name; }

class RejectionWarpTest : public testing::TestWithParam<RejectionWarp> {};

INSTANTIATE_TEST_SUITE_P(Warp, RejectionWarpTest, testing::ValuesIn(rejection_warps()),
                         [](const testing::TestParamInfo<RejectionWarp>& row) { return row.param.name; });

TEST_P(RejectionWarpTest, Chi2) {
  // The harness's u is ignored: the samples come from a generator of their own, seeded per row. Bins on the
  // support only, as in DirectionWarpTest, so one sample below the hemisphere fails the test.
  const RejectionWarp& w = GetParam();
  CountingRng rng(w.seed);
  Chi2Options options = chi2_options(w.seed);
  options.cos_theta_min = w.cos_theta_min;
  const Chi2Result r = chi2_test([&](const Vec2&) { return std::optional(w.sample(rng)); },
                                 [&](const Vec3& d) { return static_cast<double>(w.pdf(d)); }, options);
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_EQ(r.lost_samples, 0);
}

TEST_P(RejectionWarpTest, PdfIntegratesToOne) {
  const RejectionWarp& w = GetParam();
  EXPECT_NEAR(integrate_pdf_over_sphere([&](const Vec3& d) { return static_cast<double>(w.pdf(d)); }, 200), 1.0, 1e-3);
}

TEST_P(RejectionWarpTest, MeanAttemptsIsFourOverPi) {
  // Each attempt draws 2 numbers and is accepted with probability p = pi/4 (the unit disk in [-1, 1]^2), so the
  // attempts per sample are geometric: mean 1/p = 4/pi (i.e. 4/pi - 1 rejections), variance (1 - p)/p^2. The
  // mean of N samples is within 5 standard errors with probability 1 - 6e-7; with N = 1e6 that bound is
  // 0.003, 0.23% of the mean: an acceptance region wrong by a quarter of a percent of its area fails.
  const RejectionWarp& w = GetParam();
  constexpr int kSamples = 1'000'000;
  CountingRng rng(w.seed + 100);
  for (int i = 0; i < kSamples; ++i) w.sample(rng);
  ASSERT_EQ(rng.draws % 2, 0);
  const double p = kPiD / 4.0;
  const double mean = static_cast<double>(rng.draws / 2) / kSamples;
  const double standard_error = std::sqrt((1.0 - p) / (p * p) / kSamples);
  EXPECT_NEAR(mean, 4.0 / kPiD, 5.0 * standard_error)
      << "rejections per sample " << mean - 1.0 << ", expected 4/pi - 1 = " << 4.0 / kPiD - 1.0;
}

// ---------------------------------------------------------------------------------------------------------
// Planar warps

TEST(Warp, Chi2DiskConcentric) {
  // Binned in (r^2, phi / 2pi), where a uniform disk density is uniform and the disk edge is a grid edge, so
  // the expected counts are exact: pdf(r^2, t) = pi * pdf_disk(p).
  const auto sample = [](const Vec2& u) -> std::optional<Vec2> {
    const Vec2 p = warp::square_to_disk_concentric(u);
    const double r2 = glm::dot(glm::dvec2(p), glm::dvec2(p));
    double phi = std::atan2(static_cast<double>(p.y), static_cast<double>(p.x));
    if (phi < 0) phi += 2.0 * kPiD;
    // Edge points (r = 1 exactly) can land an ulp outside; DiskConcentricPdfIsPositiveOnTheEdge checks them.
    return Vec2(static_cast<float>(r2 <= 1.0 + 1e-6 ? std::min(r2, 1.0) : r2), static_cast<float>(phi / (2 * kPiD)));
  };
  const auto pdf = [](const Vec2& q) {
    const double r = std::sqrt(static_cast<double>(q.x)), phi = 2.0 * kPiD * q.y;
    return kPiD * warp::square_to_disk_concentric_pdf(Vec2(r * std::cos(phi), r * std::sin(phi)));
  };
  const Chi2Result r = chi2_test_2d(sample, pdf, {.x_bins = 40, .y_bins = 80}, chi2_options(21));
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_integral, 1.0, 1e-6);
}

TEST(Warp, DiskConcentricInvertRoundTrips) {
  double worst = 0;
  for (const Vec2& u : midpoint_grid(64)) {
    const Vec2 v = warp::disk_concentric_to_square(warp::square_to_disk_concentric(u));
    worst = std::max(worst, static_cast<double>(std::max(std::abs(v.x - u.x), std::abs(v.y - u.y))));
  }
  EXPECT_LT(worst, 1e-4);
  // The centre and the edges of the square (the seams of the octants) too.
  for (int i = 0; i <= 16; ++i) {
    const float t = i / 16.0f;
    for (const Vec2& u : {Vec2(t, 0), Vec2(0, t), Vec2(t, 1), Vec2(1, t), Vec2(t, t), Vec2(t, 1 - t), Vec2(0.5f)}) {
      const Vec2 v = warp::disk_concentric_to_square(warp::square_to_disk_concentric(u));
      EXPECT_NEAR(v.x, u.x, 1e-4) << "u = (" << u.x << ", " << u.y << ")";
      EXPECT_NEAR(v.y, u.y, 1e-4) << "u = (" << u.x << ", " << u.y << ")";
    }
  }
}

TEST(Warp, DiskConcentricPdf) {
  EXPECT_FLOAT_EQ(warp::square_to_disk_concentric_pdf(Vec2(0)), 1.0f / kPi);
  EXPECT_FLOAT_EQ(warp::square_to_disk_concentric_pdf(Vec2(0.6f, -0.79f)), 1.0f / kPi);
  EXPECT_EQ(warp::square_to_disk_concentric_pdf(Vec2(0.71f, 0.71f)), 0.0f);
  EXPECT_EQ(warp::square_to_disk_concentric_pdf(Vec2(-1.001f, 0)), 0.0f);
}

TEST(Warp, DiskConcentricPdfIsPositiveOnTheEdge) {
  // u = 0 (which Pcg32::next_float and the Sampler both return) maps to r = 1 exactly, and rounding in
  // r * (cos, sin) leaves some of those points an ulp outside the unit disk, where the pdf says 0: a sampled
  // point with pdf 0 (an infinite estimate). Every edge point of the square, on the 2^-24 grid, is checked.
  int64_t zero_pdf = 0;
  Vec2 first(-1);
  for (uint32_t k = 0; k < kUnitFloatCount; ++k) {
    for (const Vec2& u : {Vec2(0, unit_float(k)), Vec2(unit_float(k), 0)}) {
      if (warp::square_to_disk_concentric_pdf(warp::square_to_disk_concentric(u)) == 0.0f) {
        if (zero_pdf++ == 0) first = u;
      }
    }
  }
  EXPECT_EQ(zero_pdf, 0) << "of " << 2 * kUnitFloatCount << " edge samples, first at u = (" << first.x << ", "
                         << first.y << ")";
}

// Triangle barycentrics (b0, b1) are binned in s = b0 + b1 and t = b0 / s, where the uniform density 2
// (per unit barycentric area) becomes 2 s with no discontinuity inside the unit square; b0 < 0, b1 < 0 or
// b0 + b1 > 1 put the point outside the grid, which fails the test.
std::optional<Vec2> triangle_to_st(const Vec2& b) {
  const double s = static_cast<double>(b.x) + b.y;
  return Vec2(static_cast<float>(s), static_cast<float>(s > 0 ? b.x / s : 0.5));
}

TEST(Warp, Chi2UniformTriangle) {
  const auto sample = [](const Vec2& u) { return triangle_to_st(warp::square_to_uniform_triangle(u)); };
  const auto pdf = [](const Vec2& q) { return 2.0 * q.x; };
  const Chi2Result r = chi2_test_2d(sample, pdf, {}, chi2_options(22));
  EXPECT_TRUE(r.passed) << r.message;
}

TEST(Warp, UniformTriangleInvertRoundTrips) {
  double worst = 0;
  for (const Vec2& u : midpoint_grid(64)) {
    const Vec2 v = warp::uniform_triangle_to_square(warp::square_to_uniform_triangle(u));
    worst = std::max(worst, static_cast<double>(std::max(std::abs(v.x - u.x), std::abs(v.y - u.y))));
  }
  EXPECT_LT(worst, 1e-6);  // the map is piecewise linear with power-of-two coefficients: nearly exact
}

TEST(Warp, Chi2Tent) {
  // 1D histogram over [-r, r]; expected counts from the tent's cdf, exactly.
  constexpr float kRadius = 1.5f;
  constexpr int kBins = 100, kSamples = 1'000'000;
  const auto cdf = [](double x) {
    const double t = x / kRadius;
    return t < 0 ? 0.5 * sqr(1.0 + t) : 1.0 - 0.5 * sqr(1.0 - t);
  };
  std::vector<double> observed(kBins, 0.0), expected(kBins);
  for (int i = 0; i < kBins; ++i)
    expected[i] =
        kSamples * (cdf(-kRadius + 2.0 * kRadius * (i + 1) / kBins) - cdf(-kRadius + 2.0 * kRadius * i / kBins));
  Pcg32 rng(23);
  for (int s = 0; s < kSamples; ++s) {
    const float x = warp::sample_tent(rng.next_float(), kRadius);
    ASSERT_TRUE(x >= -kRadius && x <= kRadius) << x;
    ++observed[std::min(static_cast<int>((x + kRadius) / (2 * kRadius) * kBins), kBins - 1)];
  }
  const Chi2Result r = chi2_test_counts(observed, expected, chi2_options(23));
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_EQ(warp::sample_tent(0.0f, kRadius), -kRadius);
  EXPECT_EQ(warp::sample_tent(0.5f, kRadius), 0.0f);
}

// ---------------------------------------------------------------------------------------------------------
// Distribution1D: 64 cells with zero cells at both ends, a run of zeros, and a bright "sun" cell followed by
// a zero cell (an environment-map row).

std::vector<float> distribution_1d_func() {
  std::vector<float> f(64);
  for (int i = 0; i < 64; ++i) f[i] = 1.0f + static_cast<float>(i * 7 % 13);
  for (int i : {0, 1, 17, 30, 31, 32, 41, 63}) f[i] = 0.0f;
  f[40] = 200.0f;
  return f;
}

TEST(Distribution1D, Chi2) {
  const std::vector<float> f = distribution_1d_func();
  const Distribution1D dist(f);
  const int n = static_cast<int>(f.size());
  constexpr int kSubBins = 4, kSamples = 1'000'000;  // sub-bins also test uniformity within each cell
  const double sum = std::accumulate(f.begin(), f.end(), 0.0);
  std::vector<double> observed(n * kSubBins, 0.0), expected(n * kSubBins);
  for (int i = 0; i < n * kSubBins; ++i) expected[i] = kSamples * f[i / kSubBins] / sum / kSubBins;
  Pcg32 rng(31);
  for (int s = 0; s < kSamples; ++s) {
    const float x = dist.sample(rng.next_float(), nullptr);
    ASSERT_TRUE(x >= 0.0f && x < 1.0f) << x;
    ++observed[static_cast<int>(static_cast<double>(x) * n * kSubBins)];
  }
  const Chi2Result r = chi2_test_counts(observed, expected, chi2_options(31), [&](size_t i) {
    return fmt::format("x in [{}, {}) (cell {}, weight {})", double(i) / (n * kSubBins), double(i + 1) / (n * kSubBins),
                       i / kSubBins, f[i / kSubBins]);
  });
  EXPECT_TRUE(r.passed) << r.message;
}

TEST(Distribution1D, PdfIsFuncOverIntegral) {
  const std::vector<float> f = distribution_1d_func();
  const Distribution1D dist(f);
  const int n = static_cast<int>(f.size());
  const double integral = std::accumulate(f.begin(), f.end(), 0.0) / n;
  EXPECT_NEAR(dist.integral(), integral, 1e-6 * integral);
  for (int i = 0; i < n; ++i)
    for (double t : {0.01, 0.5, 0.99}) {
      const float x = static_cast<float>((i + t) / n);
      EXPECT_NEAR(dist.pdf(x), f[i] / integral, 1e-6 * f[i] / integral) << "cell " << i;
    }
}

TEST(Distribution1D, InvertRoundTrips) {
  // Float cdf: ~n ulps of error at most, so 1e-5 is loose but far below one cell (1/64).
  const Distribution1D dist(distribution_1d_func());
  double worst = 0;
  for (int k = 0; k < 4096; ++k) {
    const float u = (k + 0.5f) / 4096;
    worst = std::max(worst, std::abs(static_cast<double>(dist.invert(dist.sample(u, nullptr))) - u));
  }
  EXPECT_LT(worst, 1e-5);
}

TEST(Distribution1D, SampleStaysInItsCell) {
  // Exhaustive over every u the samplers produce: the cell that really contains x and the cell reported must
  // have weight, and the returned pdf must be pdf(x). A failure means (i + du) / n rounded over a cell edge,
  // possibly into a zero-weight cell (here cell 41, after the bright cell 40).
  const std::vector<float> f = distribution_1d_func();
  const Distribution1D dist(f);
  const size_t n = f.size();
  int64_t bad = 0, in_zero_cell = 0;
  std::string examples;
  for (uint32_t k = 0; k < kUnitFloatCount; ++k) {
    const float u = unit_float(k);
    float pdf = 0;
    uint32_t cell = 0;
    const float x = dist.sample(u, &pdf, &cell);
    const size_t containing = static_cast<size_t>(static_cast<double>(x) * n);  // exact: x is a float, n small
    const bool zero = f[containing] == 0.0f || f[cell] == 0.0f;
    if (zero || pdf != dist.pdf(x) || !(pdf > 0.0f)) {
      in_zero_cell += zero;
      // The first few cases, and the first that lands in a zero-weight cell.
      if (bad++ < 3 || (zero && in_zero_cell == 1))
        examples += fmt::format(
            "\n  u = {:.9g}: x = {:.9g} lies in cell {} (weight {}), reported cell {}, pdf {} vs "
            "pdf(x) {}",
            u, x, containing, f[containing], cell, pdf, dist.pdf(x));
    }
  }
  EXPECT_EQ(bad, 0) << "(" << in_zero_cell << " in a zero-weight cell); cases:" << examples;
}

TEST(Distribution1D, GuidedSearchInvertsTheCdfForEveryU) {
  // An environment row's size (4096 cells): uneven weights, runs of zeros, a sun 10^5 times the rest, so that the
  // guide table's entries bunch up and skip. Exhaustive over every u the samplers produce: the sample must be where
  // the cdf reaches u (invert(x) = u to float rounding; a wrong cell is off by its width, 2.4e-4 or more here, or by
  // the sun's mass), in a cell with weight, and x must not decrease as u grows. Float rounding: x's spacing (one ulp)
  // and invert's x n each move invert(x) by up to the cell's mass times n ulp(x): 2.4e-4 in the sun's cell.
  constexpr size_t kCells = 4096;
  std::vector<float> f(kCells);
  for (size_t i = 0; i < kCells; ++i) f[i] = 1.0f + static_cast<float>(i * 7919 % 101);
  std::fill(f.begin(), f.begin() + 300, 0.0f);
  std::fill(f.begin() + 2000, f.begin() + 2003, 0.0f);
  f[2003] = 1e7f;
  f.back() = 0.0f;
  const Distribution1D dist(f);
  const double sum = std::accumulate(f.begin(), f.end(), 0.0);
  double worst = 0;  // the largest error in units of its rounding bound
  float worst_u = 0, last_x = 0;
  int64_t zero_cells = 0, decreasing = 0;
  for (uint32_t k = 0; k < kUnitFloatCount; ++k) {
    const float u = unit_float(k);
    uint32_t cell = 0;
    const float x = dist.sample(u, nullptr, &cell);
    const double mass = f[cell] / sum, ulp = std::nextafter(x, 2.0f) - x;
    const double err = std::abs(static_cast<double>(dist.invert(x)) - u) / (1e-6 + 2.0 * mass * kCells * ulp);
    if (err > worst) worst = err, worst_u = u;
    zero_cells += f[cell] == 0.0f;
    decreasing += x < last_x;
    last_x = x;
  }
  EXPECT_LT(worst, 1.0) << "at u = " << worst_u;
  EXPECT_EQ(zero_cells, 0);
  EXPECT_EQ(decreasing, 0);
}

// ---------------------------------------------------------------------------------------------------------
// Distribution2D: 8 x 6 cells shaped like a small environment map: a black bottom row, a few black cells,
// and a sun next to a black cell.

constexpr int kNu = 8, kNv = 6;

std::vector<float> distribution_2d_func() {
  std::vector<float> f(kNu * kNv);
  for (int v = 0; v < kNv; ++v)
    for (int u = 0; u < kNu; ++u) f[v * kNu + u] = 0.5f + static_cast<float>((3 * u + 5 * v) % 7);
  for (int u = 0; u < kNu; ++u) f[5 * kNu + u] = 0.0f;  // the ground
  for (int i : {0, 9, 10, 4 * kNu + 4}) f[i] = 0.0f;
  f[4 * kNu + 3] = 60.0f;  // the sun
  return f;
}

TEST(Distribution2D, Chi2) {
  const std::vector<float> f = distribution_2d_func();
  const Distribution2D dist(f, kNu, kNv);
  const double total = std::accumulate(f.begin(), f.end(), 0.0) / (kNu * kNv);
  // The pdf from the definition, f / integral; 4 x 4 bins per cell keep the cell edges on bin edges.
  const auto pdf = [&](const Vec2& p) {
    return f[static_cast<int>(p.y * kNv) * kNu + static_cast<int>(p.x * kNu)] / total;
  };
  const Chi2Result r = chi2_test_2d([&](const Vec2& u) { return std::optional(dist.sample(u, nullptr)); }, pdf,
                                    {.x_bins = 4 * kNu, .y_bins = 4 * kNv}, chi2_options(32));
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(dist.integral(), total, 1e-6 * total);
}

TEST(Distribution2D, PdfIsFuncOverIntegral) {
  const std::vector<float> f = distribution_2d_func();
  const Distribution2D dist(f, kNu, kNv);
  const double total = std::accumulate(f.begin(), f.end(), 0.0) / (kNu * kNv);
  for (int v = 0; v < kNv; ++v)
    for (int u = 0; u < kNu; ++u) {
      const Vec2 p((u + 0.3f) / kNu, (v + 0.7f) / kNv);
      const double expected = f[v * kNu + u] / total;
      EXPECT_NEAR(dist.pdf(p), expected, 1e-6 * expected) << "cell " << u << ", " << v;
    }
  // The pdf returned by sample() is pdf() at the sample.
  for (const Vec2& u : midpoint_grid(64)) {
    float pdf = 0;
    const Vec2 p = dist.sample(u, &pdf);
    EXPECT_FLOAT_EQ(pdf, dist.pdf(p)) << "u = (" << u.x << ", " << u.y << ")";
  }
}

TEST(Distribution2D, InvertRoundTrips) {
  const Distribution2D dist(distribution_2d_func(), kNu, kNv);
  double worst = 0;
  for (const Vec2& u : midpoint_grid(128)) {
    const Vec2 v = dist.invert(dist.sample(u, nullptr));
    worst = std::max(worst, static_cast<double>(std::max(std::abs(v.x - u.x), std::abs(v.y - u.y))));
  }
  EXPECT_LT(worst, 1e-5);
}

// Every u on the 2^-24 grid within 64 steps of u0: where rounding at a cdf boundary can go wrong.
std::vector<float> grid_around(float u0) {
  std::vector<float> values;
  const int64_t k0 = std::llround(static_cast<double>(u0) * kUnitFloatCount);
  for (int64_t k = std::max<int64_t>(0, k0 - 64); k <= std::min<int64_t>(kUnitFloatCount - 1, k0 + 64); ++k)
    values.push_back(unit_float(static_cast<uint32_t>(k)));
  return values;
}

TEST(Distribution2D, SampleStaysInItsCell) {
  // As for Distribution1D, but only near the cdf boundaries (found with invert) of the marginal and of every
  // row's conditional: the sample must not land in a zero cell, and its pdf must be pdf(p).
  const std::vector<float> f = distribution_2d_func();
  const Distribution2D dist(f, kNu, kNv);
  int64_t bad = 0;
  std::string examples;
  std::set<std::pair<float, float>> checked;  // boundaries of zero-width cells coincide
  const auto check = [&](const Vec2& u) {
    if (!checked.emplace(u.x, u.y).second) return;
    float pdf = 0;
    const Vec2 p = dist.sample(u, &pdf);
    const int col = static_cast<int>(static_cast<double>(p.x) * kNu);
    const int row = static_cast<int>(static_cast<double>(p.y) * kNv);
    // sample() multiplies two pdfs where pdf() divides once: they may differ by float rounding only.
    if (f[row * kNu + col] == 0.0f || !(pdf > 0.0f) || std::abs(pdf - dist.pdf(p)) > 1e-6f * pdf) {
      if (bad++ < 4)
        examples += fmt::format(
            "\n  u = ({:.9g}, {:.9g}) -> p = ({:.9g}, {:.9g}) in cell ({}, {}) of weight {}, pdf {} "
            "vs pdf(p) {}",
            u.x, u.y, p.x, p.y, col, row, f[row * kNu + col], pdf, dist.pdf(p));
    }
  };
  for (int k = 0; k <= kNv; ++k)
    for (float v : grid_around(dist.invert(Vec2(0.5f, static_cast<float>(k) / kNv)).y)) check(Vec2(0.5f, v));
  for (int row = 0; row < kNv; ++row) {
    if (std::all_of(f.begin() + row * kNu, f.begin() + (row + 1) * kNu, [](float x) { return x == 0.0f; })) continue;
    const float y = (row + 0.5f) / kNv;
    const float v = dist.invert(Vec2(0.5f, y)).y;  // a u.y that selects this row
    for (int k = 0; k <= kNu; ++k)
      for (float u : grid_around(dist.invert(Vec2(static_cast<float>(k) / kNu, y)).x)) check(Vec2(u, v));
  }
  EXPECT_GT(checked.size(), 5000U);
  EXPECT_EQ(bad, 0) << "first cases:" << examples;
}

// ---------------------------------------------------------------------------------------------------------
// AliasTable: 37 weights with zeros at both ends, a negative weight (treated as 0) and a dominant one.

std::vector<float> alias_weights() {
  std::vector<float> w(37);
  for (int i = 0; i < 37; ++i) w[i] = 0.25f + static_cast<float>(i * 11 % 17);
  for (int i : {0, 5, 6, 36}) w[i] = 0.0f;
  w[20] = -3.0f;
  w[12] = 150.0f;
  return w;
}

double positive_sum(const std::vector<float>& w) {
  return std::accumulate(w.begin(), w.end(), 0.0, [](double a, float b) { return a + std::max(0.0f, b); });
}

TEST(AliasTable, Chi2) {
  const std::vector<float> w = alias_weights();
  const AliasTable table(w);
  const double sum = positive_sum(w);
  constexpr int kSamples = 1'000'000;
  std::vector<double> observed(w.size(), 0.0), expected(w.size());
  for (size_t i = 0; i < w.size(); ++i) expected[i] = kSamples * std::max(0.0f, w[i]) / sum;
  Pcg32 rng(33);
  for (int s = 0; s < kSamples; ++s) {
    const uint32_t i = table.sample(rng.next_float());
    ASSERT_LT(i, w.size());
    ++observed[i];
  }
  const Chi2Result r = chi2_test_counts(observed, expected, chi2_options(33),
                                        [&](size_t i) { return fmt::format("index {} (weight {})", i, w[i]); });
  EXPECT_TRUE(r.passed) << r.message;
}

TEST(AliasTable, PmfIsWeightOverSum) {
  const std::vector<float> w = alias_weights();
  const AliasTable table(w);
  const double sum = positive_sum(w);
  ASSERT_EQ(table.size(), w.size());
  for (uint32_t i = 0; i < w.size(); ++i) EXPECT_NEAR(table.pmf(i), std::max(0.0f, w[i]) / sum, 1e-7) << i;
}

TEST(AliasTable, ExhaustiveFrequenciesMatchPmfAndZerosAreNeverSampled) {
  // Over every u on the 2^-24 grid the frequencies are deterministic: each index's share may differ from its
  // pmf only by rounding of the float thresholds (a few grid points per bin, ~1e-7), never by a sample of a
  // zero weight.
  const std::vector<float> w = alias_weights();
  const AliasTable table(w);
  const double sum = positive_sum(w);
  std::vector<int64_t> counts(w.size(), 0);
  for (uint32_t k = 0; k < kUnitFloatCount; ++k) ++counts[table.sample(unit_float(k))];
  for (size_t i = 0; i < w.size(); ++i) {
    if (w[i] <= 0.0f) {
      EXPECT_EQ(counts[i], 0) << "zero-weight index " << i;
    }
    EXPECT_NEAR(static_cast<double>(counts[i]) / kUnitFloatCount, std::max(0.0f, w[i]) / sum, 1e-6) << "index " << i;
  }
}

TEST(AliasTable, AllZeroWeightsFallBackToUniform) {
  const std::vector<float> w(5, 0.0f);
  const AliasTable table(w);
  std::vector<int> counts(5, 0);
  for (int k = 0; k < 5000; ++k) ++counts[table.sample((k + 0.5f) / 5000)];
  for (uint32_t i = 0; i < 5; ++i) {
    EXPECT_FLOAT_EQ(table.pmf(i), 0.2f);
    EXPECT_EQ(counts[i], 1000);
  }
}

// ---------------------------------------------------------------------------------------------------------
// Sampler (Owen-scrambled Sobol)

// The first 2^k points of one dimension pair, at one pixel.
std::vector<Vec2> sobol_points(uint32_t px, uint32_t py, uint32_t dimension, uint32_t first, uint32_t count) {
  Sampler sampler(7);
  std::vector<Vec2> points;
  for (uint32_t i = first; i < first + count; ++i) {
    sampler.start(px, py, i);
    for (uint32_t d = 0; d < dimension; ++d) sampler.next_1d();
    points.push_back(sampler.next_2d());
  }
  return points;
}

// (0, m, 2)-net: each of the 2^m elementary intervals of every shape 2^-i x 2^-(m-i) holds exactly one point.
std::string net_violation(const std::vector<Vec2>& points, int m) {
  for (int i = 0; i <= m; ++i) {
    std::set<uint32_t> cells;
    for (const Vec2& p : points) {
      EXPECT_TRUE(p.x >= 0.0f && p.x < 1.0f && p.y >= 0.0f && p.y < 1.0f);
      const uint32_t cx = static_cast<uint32_t>(p.x * static_cast<float>(1U << i));  // exact: power-of-two scale
      const uint32_t cy = static_cast<uint32_t>(p.y * static_cast<float>(1U << (m - i)));
      if (!cells.insert(cx << (m - i) | cy).second)
        return fmt::format("two points in the interval {} / 2^{} x {} / 2^{}", cx, i, cy, m - i);
    }
  }
  return {};
}

TEST(Sampler, FirstPointsOfEveryPixelFormANet) {
  for (int m : {4, 8}) {
    for (const Vec2i pixel : {Vec2i(0, 0), Vec2i(1, 0), Vec2i(0, 1), Vec2i(17, 93), Vec2i(4095, 2047)}) {
      for (uint32_t dimension : {0U, 1U, 2U, 5U, 12U}) {
        const std::vector<Vec2> points = sobol_points(pixel.x, pixel.y, dimension, 0, 1U << m);
        EXPECT_EQ(net_violation(points, m), "")
            << "m " << m << ", pixel " << pixel.x << "," << pixel.y << ", dim " << dimension;
      }
    }
  }
}

TEST(Sampler, LaterAlignedBlocksFormANetToo) {
  // A (0, 2)-sequence: every aligned block of 2^m consecutive samples is a (0, m, 2)-net.
  for (uint32_t block : {1U, 3U, 10U}) {
    EXPECT_EQ(net_violation(sobol_points(5, 9, 3, block * 16, 16), 4), "") << "block " << block;
    EXPECT_EQ(net_violation(sobol_points(5, 9, 3, block * 256, 256), 8), "") << "block " << block;
  }
}

TEST(Sampler, OneDimensionIsStratified) {
  for (uint32_t dimension : {0U, 1U, 4U}) {
    Sampler sampler(7);
    std::set<uint32_t> cells;
    for (uint32_t i = 0; i < 256; ++i) {
      sampler.start(3, 4, i);
      for (uint32_t d = 0; d < dimension; ++d) sampler.next_2d();
      cells.insert(static_cast<uint32_t>(sampler.next_1d() * 256.0f));
    }
    EXPECT_EQ(cells.size(), 256U) << "dimension " << dimension;
  }
}

TEST(Sampler, PixelsAndDimensionsGetDifferentSequences) {
  // The first two points of several dimensions at every pixel of a 16 x 16 block (so at (x, y) and (y, x) both)
  // are all distinct: independent scrambles coincide with probability ~2^-48 per pair, so any coincidence is a
  // seeding bug (e.g. a pixel hash symmetric in x and y).
  std::set<std::vector<std::pair<float, float>>> sequences;
  int count = 0;
  for (uint32_t py = 0; py < 16; ++py)
    for (uint32_t px = 0; px < 16; ++px)
      for (uint32_t dimension : {0U, 1U, 7U}) {
        std::vector<std::pair<float, float>> sequence;
        for (const Vec2& p : sobol_points(px, py, dimension, 0, 2)) sequence.emplace_back(p.x, p.y);
        sequences.insert(sequence);
        ++count;
      }
  EXPECT_EQ(sequences.size(), static_cast<size_t>(count));
  // ...and the same (pixel, index, dimension) always gives the same value.
  EXPECT_EQ(sobol_points(17, 93, 2, 5, 4), sobol_points(17, 93, 2, 5, 4));
}

TEST(Sampler, Next4dEqualsItsPortableFormBitForBit) {
  // next_4d's SIMD lanes (SSE4.1, GFNI or a nibble table) against the scalar code, over seeds, pixels, sample indices
  // (every byte of the index in play) and dimensions; where the build has no SSE4.1 both are the scalar code.
  int mismatches = 0, compared = 0;
  for (uint32_t seed : {0U, 7U, 0xdeadbeefU})
    for (const Vec2i pixel : {Vec2i(0, 0), Vec2i(17, 93), Vec2i(4095, 2047)})
      for (uint32_t index : {0U, 1U, 255U, 256U, 65537U, 0x00ffffffU, 0x12345678U, 0xffffffffU}) {
        Sampler a(seed), b(seed);
        a.start(pixel.x, pixel.y, index);
        b.start(pixel.x, pixel.y, index);
        for (int d = 0; d < 24; ++d) {
          const Vec4 simd = a.next_4d(), portable = b.next_4d_portable();
          for (int c = 0; c < 4; ++c) {
            ++compared;
            if (std::memcmp(&simd[c], &portable[c], sizeof(float)) != 0) ++mismatches;
          }
        }
      }
  EXPECT_EQ(mismatches, 0) << "of " << compared;
}

#if defined(__SSE4_1__)
TEST(Sampler, BitReversalOfFourLanesMatchesTheScalarOne) {
  // Both four-lane forms (GFNI where the CPU has it, and the nibble table used where it does not) against
  // reverse_bits, lane by lane: single bits, every byte value in every byte position, and hashed values.
  std::vector<uint32_t> values;
  for (int b = 0; b < 32; ++b) values.push_back(1u << b);
  for (uint32_t v = 0; v < 256; ++v)
    for (int shift = 0; shift < 32; shift += 8) values.push_back(v << shift);
  for (uint32_t k = 0; k < 4096; ++k) values.push_back(hash_u32(k));
  while (values.size() % 4 != 0) values.push_back(0xffffffffu);
  int mismatches = 0;
  for (size_t i = 0; i < values.size(); i += 4) {
    const __m128i x = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&values[i]));
    for (const __m128i r : {sobol::reverse_bits4(x), sobol::reverse_bits4_by_table(x)}) {
      alignas(16) uint32_t out[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(out), r);
      for (int lane = 0; lane < 4; ++lane)
        if (out[lane] != sobol::reverse_bits(values[i + lane])) ++mismatches;
    }
  }
  EXPECT_EQ(mismatches, 0) << "of " << 2 * values.size();
}
#endif

TEST(Sampler, Next4dIsStratified) {
  // Components (0, 1) of next_4d are a (0, 2)-sequence: the first 256 points form a (0, 8, 2)-net (the pairs that
  // need the best 2-D stratification go there); z and w, Sobol dimensions 2 and 3, are each stratified in 1-D (as a
  // pair they are not a (0, 2)-net, which the 2-D check would find). At several dimension slots.
  for (uint32_t dimension : {0U, 3U, 9U}) {
    std::vector<Vec2> xy;
    std::set<uint32_t> z_cells, w_cells;
    Sampler sampler(11);
    for (uint32_t i = 0; i < 256; ++i) {
      sampler.start(8, 5, i);
      for (uint32_t d = 0; d < dimension; ++d) sampler.next_4d();
      const Vec4 u = sampler.next_4d();
      xy.emplace_back(u.x, u.y);
      z_cells.insert(static_cast<uint32_t>(u.z * 256.0f));
      w_cells.insert(static_cast<uint32_t>(u.w * 256.0f));
    }
    EXPECT_EQ(net_violation(xy, 8), "") << "dimension " << dimension;
    EXPECT_EQ(z_cells.size(), 256U) << "dimension " << dimension;
    EXPECT_EQ(w_cells.size(), 256U) << "dimension " << dimension;
  }
}

}  // namespace
}  // namespace kozu::test

namespace kozu::test {
namespace {

// fast_atan2 (core/math.h) against the double-precision atan2 over the whole circle, at every quadrant's edges and
// signed zeros. The bound, 4.9e-7 rad, is what its parts add up to: the polynomial's fit error (1.2e-7), the ratio's
// rounding through atan's slope (at most 0.6e-7), the float constants pi / 2 and pi (4.4e-8 and 8.7e-8 from their
// values) and two roundings (half a float ulp in [1, 2) and in [2, 4): 0.6e-7 and 1.2e-7). Measured: 2.91e-7 with
// GCC's fused multiply-adds, 3.00e-7 with clang's separate ones (the sanitizer build). On the axes it gives
// std::atan2's values, so a map from directions keeps its seams where the libm one had them.
TEST(FastAtan2, MatchesAtan2AcrossTheCircle) {
  double worst = 0.0, worst_excess = 0.0;
  Pcg32 rng(11);
  for (int i = 0; i < 2000000; ++i) {
    const float a = static_cast<float>(2.0 * kPiD * (i + 0.5) / 2000000.0);
    const float r = i % 2 ? 1.0f : std::ldexp(1.0f + rng.next_float(), static_cast<int>(rng.next_u32() % 200) - 100);
    const float x = r * std::cos(a), y = r * std::sin(a);
    const double want = std::atan2(double(y), double(x));
    const auto error = [&](float got) {
      const double e = std::abs(double(got) - want);
      return std::min(e, 2.0 * kPiD - e);  // ±pi on the negative x axis are one angle
    };
    const double err = error(fast_atan2(y, x));
    worst = std::max(worst, err);
    worst_excess = std::max(worst_excess, err - error(std::atan2(y, x)));
  }
  std::printf("fast_atan2: largest error %.3g rad, largest excess over std::atan2f %.3g rad\n", worst, worst_excess);
  const double bound = 1.2e-7 + 0.6e-7 + 4.4e-8 + 8.7e-8 + 0.6e-7 + 1.2e-7;
  EXPECT_LT(worst, bound);
  EXPECT_LT(worst_excess, bound);
  const float axes[][2] = {{0.0f, 1.0f}, {1.0f, 0.0f}, {0.0f, -1.0f}, {-1.0f, 0.0f}, {-0.0f, -1.0f}, {0.0f, 0.0f},
                           {-0.0f, 0.0f}, {0.0f, -0.0f}, {-0.0f, -0.0f}, {3.0f, 3.0f}, {-2.0f, 2.0f}};
  for (const auto& p : axes) {
    SCOPED_TRACE(fmt::format("atan2({}, {})", p[0], p[1]));
    EXPECT_NEAR(fast_atan2(p[0], p[1]), std::atan2(p[0], p[1]), 1e-7f);
    EXPECT_EQ(std::signbit(fast_atan2(p[0], p[1])), std::signbit(std::atan2(p[0], p[1])));
  }
  EXPECT_TRUE(std::isnan(fast_atan2(std::nanf(""), 1.0f)));
  EXPECT_TRUE(std::isnan(fast_atan2(1.0f, std::nanf(""))));
}

}  // namespace
}  // namespace kozu::test
