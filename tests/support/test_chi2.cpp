// Tests of the chi-square harness itself: the p-value function against known values, the pooling and
// statistic on hand-computed histograms, and end-to-end runs showing that it passes correct samplers, is
// calibrated (uniform p-values) under the null hypothesis, and fails samplers or pdfs that are subtly wrong.
#include "support/chi2.h"

#include "core/warp.h"

#include <gtest/gtest.h>

#include <numbers>
#include <vector>

namespace kozu::test {
namespace {

// Šidák family: the chi-square runs in this file whose outcome is random and that must pass.
constexpr int kChi2Tests = 5;

Chi2Options options_for_file() {
  Chi2Options options;
  options.test_count = kChi2Tests;
  return options;
}

std::optional<Vec3> uniform_sphere(const Vec2& u) { return warp::square_to_uniform_sphere(u); }
double uniform_sphere_pdf(const Vec3&) { return 1.0 / (4.0 * std::numbers::pi); }

// Directions with density proportional to cos^n(theta) on the upper hemisphere: cos(theta) = u^(1/(n+1)).
DirectionSampler power_cosine_sampler(double n) {
  return [n](const Vec2& u) -> std::optional<Vec3> {
    const double z = std::pow(static_cast<double>(u.x), 1.0 / (n + 1.0));
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z)), phi = 2.0 * std::numbers::pi * u.y;
    return Vec3(static_cast<float>(r * std::cos(phi)), static_cast<float>(r * std::sin(phi)), static_cast<float>(z));
  };
}
double cosine_pdf(const Vec3& w) { return w.z > 0 ? w.z / std::numbers::pi : 0.0; }

// Density 2x on the unit square.
double linear_pdf(const Vec2& p) { return 2.0 * p.x; }

// ---------------------------------------------------------------------------------------------------------
// chi2_survival

TEST(Chi2Survival, KnownQuantiles) {
  // Upper 5% points of the chi-square distribution (standard tables).
  EXPECT_NEAR(chi2_survival(3.841459, 1), 0.05, 1e-5);
  EXPECT_NEAR(chi2_survival(18.307038, 10), 0.05, 1e-5);
  EXPECT_NEAR(chi2_survival(124.342, 100), 0.05, 1e-5);
  // Upper 1% points.
  EXPECT_NEAR(chi2_survival(6.634897, 1), 0.01, 1e-6);
  EXPECT_NEAR(chi2_survival(135.807, 100), 0.01, 1e-5);
}

TEST(Chi2Survival, EvenDofMatchesClosedForm) {
  // For dof = 2m: Q(m, x/2) = exp(-x/2) * sum_{j<m} (x/2)^j / j!. Evaluated in log space so it holds for
  // dof in the thousands; x spans both the series (x/2 < m + 1) and continued fraction branches.
  for (int dof : {2, 4, 10, 50, 200, 1000, 3000}) {
    for (double scale : {0.2, 0.8, 0.95, 1.0, 1.05, 1.2, 2.0}) {
      const double x = scale * dof, half = 0.5 * x;
      double expected = 0;
      for (int j = 0; j < dof / 2; ++j) expected += std::exp(-half + j * std::log(half) - std::lgamma(j + 1.0));
      EXPECT_NEAR(chi2_survival(x, dof), expected, 1e-10 + 1e-9 * expected) << "dof " << dof << ", x " << x;
    }
  }
}

TEST(Chi2Survival, OddDofMatchesErfcRecurrence) {
  // Q(1/2, x) = erfc(sqrt(x)) and Q(a + 1, x) = Q(a, x) + x^a exp(-x) / Gamma(a + 1).
  for (double x : {0.01, 0.5, 1.0, 3.0, 7.5, 20.0, 60.0}) {
    const double half = 0.5 * x;
    double q = std::erfc(std::sqrt(half));
    for (int dof = 1; dof <= 61; dof += 2) {
      EXPECT_NEAR(chi2_survival(x, dof), q, 1e-12 + 1e-10 * q) << "dof " << dof << ", x " << x;
      const double a = 0.5 * dof;
      q += std::exp(a * std::log(half) - half - std::lgamma(a + 1.0));
    }
  }
}

TEST(Chi2Survival, LimitsAndMonotonicity) {
  EXPECT_EQ(chi2_survival(0.0, 7), 1.0);
  EXPECT_LT(chi2_survival(1e4, 10), 1e-300);
  EXPECT_TRUE(std::isnan(chi2_survival(1.0, 0)));
  double previous = 1.0;
  for (double x = 0.5; x < 400.0; x += 0.5) {
    const double q = chi2_survival(x, 100);
    EXPECT_LE(q, previous) << "x " << x;
    previous = q;
  }
}

// ---------------------------------------------------------------------------------------------------------
// chi2_test_counts: statistic, degrees of freedom and pooling on hand-computed cases

TEST(Chi2Counts, StatisticAndPValue) {
  const std::vector<double> observed{10, 20, 30}, expected{20, 20, 20};
  const Chi2Result r = chi2_test_counts(observed, expected);
  EXPECT_DOUBLE_EQ(r.statistic, 10.0);
  EXPECT_EQ(r.degrees_of_freedom, 2);
  EXPECT_NEAR(r.p_value, std::exp(-5.0), 1e-14);  // dof 2: Q = exp(-chi2 / 2)
  EXPECT_FALSE(r.passed);                         // 0.0067 < 0.01
  EXPECT_NE(r.message.find("worst cells"), std::string::npos) << r.message;
}

TEST(Chi2Counts, PoolsSmallCellsInIncreasingOrder) {
  // Cells expecting 1, 2, 3 pool into one cell (O = 7, E = 6); the rest are tested alone.
  const std::vector<double> observed{45, 2, 55, 1, 49, 4}, expected{50, 1, 50, 2, 50, 3};
  const Chi2Result r = chi2_test_counts(observed, expected);
  EXPECT_NEAR(r.statistic, 25.0 / 50 + 25.0 / 50 + 1.0 / 50 + 1.0 / 6, 1e-12);
  EXPECT_EQ(r.degrees_of_freedom, 3);
  EXPECT_TRUE(r.passed) << r.message;
}

TEST(Chi2Counts, KeepsPoolingUntilThePoolIsLargeEnough) {
  // The pool holds 1 after the first cell, so the cell expecting 6 joins it although 6 >= min_expected.
  const std::vector<double> observed{3, 9, 40, 60}, expected{1, 6, 50, 50};
  const Chi2Result r = chi2_test_counts(observed, expected);
  EXPECT_NEAR(r.statistic, 25.0 / 7 + 100.0 / 50 + 100.0 / 50, 1e-12);
  EXPECT_EQ(r.degrees_of_freedom, 2);
}

TEST(Chi2Counts, SampleWherePdfIsZeroFailsOutright) {
  const std::vector<double> observed{50, 1, 49}, expected{50, 0, 50};
  const Chi2Result r = chi2_test_counts(observed, expected, {}, [](size_t i) { return "bin #" + std::to_string(i); });
  EXPECT_FALSE(r.passed);
  EXPECT_NE(r.message.find("region with pdf 0, bin #1"), std::string::npos) << r.message;
}

TEST(Chi2Counts, NoPowerFails) {
  // Everything pools into one cell: zero degrees of freedom cannot reject anything, so it must not pass.
  const std::vector<double> observed{1, 2}, expected{1.5, 1.5};
  const Chi2Result r = chi2_test_counts(observed, expected);
  EXPECT_FALSE(r.passed);
  EXPECT_NE(r.message.find("no power"), std::string::npos) << r.message;
}

TEST(Chi2Counts, SidakThreshold) {
  Chi2Options options;
  options.significance = 0.01;
  options.test_count = 20;
  const std::vector<double> observed{10, 20, 30}, expected{20, 20, 20};
  const Chi2Result r = chi2_test_counts(observed, expected, options);
  EXPECT_NEAR(r.threshold, 1.0 - std::pow(0.99, 1.0 / 20.0), 1e-15);
  EXPECT_TRUE(r.passed) << r.message;  // p = 0.0067 passes at the corrected level 0.0005
}

// ---------------------------------------------------------------------------------------------------------
// integrate_pdf_over_sphere

TEST(Chi2Integrate, PolynomialsOnTheSphereAreExact) {
  EXPECT_NEAR(integrate_pdf_over_sphere([](const Vec3&) { return 1.0; }, 4), 4.0 * std::numbers::pi, 1e-12);
  // The directions are floats, so integrands in w are exact to float precision only.
  EXPECT_NEAR(integrate_pdf_over_sphere([](const Vec3& w) { return double(w.z) * w.z; }, 4), 4.0 * std::numbers::pi / 3,
              1e-6);
  EXPECT_NEAR(integrate_pdf_over_sphere([](const Vec3& w) { return double(w.x) * w.x; }, 4), 4.0 * std::numbers::pi / 3,
              1e-6);
  EXPECT_NEAR(integrate_pdf_over_sphere([](const Vec3& w) { return 1.0 + w.y; }, 4), 4.0 * std::numbers::pi, 1e-6);
}

TEST(Chi2Integrate, InvalidPdfGivesNaN) {
  EXPECT_TRUE(std::isnan(integrate_pdf_over_sphere([](const Vec3& w) { return w.z; }, 4)));
}

// ---------------------------------------------------------------------------------------------------------
// chi2_test: correct samplers pass (these are the kChi2Tests family)

TEST(Chi2Harness, UniformSpherePasses) {
  const Chi2Result r = chi2_test(uniform_sphere, uniform_sphere_pdf, options_for_file());
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_integral, 1.0, 1e-9);
  // 40 x 80 cells, minus one; the empty rejected-sample cell adds no degree of freedom.
  EXPECT_EQ(r.degrees_of_freedom, 40 * 80 - 1);
}

TEST(Chi2Harness, CosinePowerSamplerPasses) {
  // A sampler written here, independent of warp.h, checked against its analytic pdf.
  const double n = 1.1;
  const auto pdf = [n](const Vec3& w) {
    return w.z > 0 ? (n + 1.0) / (2.0 * std::numbers::pi) * std::pow(double(w.z), n) : 0.0;
  };
  const Chi2Result r = chi2_test(power_cosine_sampler(n), pdf, options_for_file());
  EXPECT_TRUE(r.passed) << r.message;
}

TEST(Chi2Harness, AccountedRejectionPasses) {
  // Rejecting the lower hemisphere loses half the mass; the pdf says so by integrating to 1/2.
  const auto sample = [](const Vec2& u) -> std::optional<Vec3> {
    const Vec3 w = warp::square_to_uniform_sphere(u);
    return w.z >= 0 ? std::optional(w) : std::nullopt;
  };
  const auto pdf = [](const Vec3& w) { return w.z >= 0 ? 1.0 / (4.0 * std::numbers::pi) : 0.0; };
  const Chi2Result r = chi2_test(sample, pdf, options_for_file());
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_integral, 0.5, 1e-9);
  EXPECT_NEAR(static_cast<double>(r.lost_samples), 5e5, 5 * 500.0);  // binomial sd = 500
}

TEST(Chi2Harness, PlanarPointsPass) {
  // The density 2x by inversion: x = sqrt(u).
  const auto sample = [](const Vec2& u) -> std::optional<Vec2> { return Vec2(std::sqrt(u.x), u.y); };
  const Chi2Result r = chi2_test_2d(sample, linear_pdf, {}, options_for_file());
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_integral, 1.0, 1e-6);
}

TEST(Chi2Harness, PValuesAreUniformUnderTheNullHypothesis) {
  // Calibration: for a correct sampler the p-value is uniform on [0, 1], whatever the pooling. Kolmogorov–
  // Smirnov test of 100 independent runs (asymptotic distribution with Stephens' small-n correction, as in
  // Numerical Recipes §14.3.3); dof or statistic errors skew the p-values and fail here.
  constexpr int kRuns = 100;
  std::vector<double> p_values;
  Chi2Options options;
  options.sample_count = 20'000;
  options.theta_bins = 10;
  options.phi_bins = 20;
  options.min_expected = 50;  // pool a fair amount: the tail cells of the cosine lobe
  for (int run = 0; run < kRuns; ++run) {
    options.seed = 1000 + run;
    const Chi2Result r = chi2_test(power_cosine_sampler(1.0), cosine_pdf, options);
    ASSERT_GT(r.degrees_of_freedom, 0) << r.message;
    p_values.push_back(r.p_value);
  }
  std::sort(p_values.begin(), p_values.end());
  double d = 0;
  for (int i = 0; i < kRuns; ++i)
    d = std::max({d, std::abs(p_values[i] - double(i) / kRuns), std::abs(p_values[i] - double(i + 1) / kRuns)});
  const double t = (std::sqrt(double(kRuns)) + 0.12 + 0.11 / std::sqrt(double(kRuns))) * d;
  double ks_p = 0;
  for (int k = 1; k <= 100; ++k) ks_p += 2.0 * ((k % 2) ? 1.0 : -1.0) * std::exp(-2.0 * k * k * t * t);
  const double threshold = 1.0 - std::pow(1.0 - options_for_file().significance, 1.0 / kChi2Tests);
  EXPECT_GE(std::min(ks_p, 1.0), threshold) << "KS distance " << d;
}

// ---------------------------------------------------------------------------------------------------------
// chi2_test: wrong samplers or pdfs fail

TEST(Chi2Harness, WrongPdfShapeFails) {
  // Normalised, but tilted by 10% towards +z: the chi-square divergence is 1/300, so the statistic exceeds
  // its dof by ~3300 at 1M samples against a standard deviation of ~80.
  const auto pdf = [](const Vec3& w) { return (1.0 + 0.1 * w.z) / (4.0 * std::numbers::pi); };
  const Chi2Result r = chi2_test(uniform_sphere, pdf, options_for_file());
  EXPECT_FALSE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_integral, 1.0, 1e-6);
  EXPECT_NE(r.message.find("worst cells"), std::string::npos) << r.message;
}

TEST(Chi2Harness, MisnormalisedPdfFails) {
  // The pdf claims 10% of the mass is rejected, but nothing is.
  const auto pdf = [](const Vec3& w) { return 0.9 * uniform_sphere_pdf(w); };
  const Chi2Result r = chi2_test(uniform_sphere, pdf, options_for_file());
  EXPECT_FALSE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_integral, 0.9, 1e-6);
}

TEST(Chi2Harness, UnaccountedRejectionFails) {
  // 0.5% of samples rejected while the pdf claims all the mass. The cells alone see a uniform 0.5% deficit
  // (statistic excess N * 0.005^2 = 25, invisible against sd ~80); the rejected-sample cell catches it.
  const auto sample = [](const Vec2& u) -> std::optional<Vec3> {
    if (u.y < 0.005f) return std::nullopt;
    return warp::square_to_uniform_sphere(Vec2(u.x, (u.y - 0.005f) / 0.995f));
  };
  const Chi2Result r = chi2_test(sample, uniform_sphere_pdf, options_for_file());
  EXPECT_FALSE(r.passed) << r.message;
  EXPECT_NE(r.message.find("rejected samples"), std::string::npos) << r.message;
}

TEST(Chi2Harness, UniformSphereAgainstCosinePdfFails) {
  // Half the samples land where the cosine pdf is 0: an immediate, unambiguous failure.
  const Chi2Result r = chi2_test(uniform_sphere, cosine_pdf, options_for_file());
  EXPECT_FALSE(r.passed) << r.message;
  EXPECT_NE(r.message.find("region with pdf 0"), std::string::npos) << r.message;
}

TEST(Chi2Harness, CosineSamplerAgainstUniformHemispherePdfFails) {
  const auto sample = [](const Vec2& u) -> std::optional<Vec3> { return warp::square_to_cosine_hemisphere(u); };
  const auto pdf = [](const Vec3& w) { return w.z >= 0 ? 1.0 / (2.0 * std::numbers::pi) : 0.0; };
  const Chi2Result r = chi2_test(sample, pdf, options_for_file());
  EXPECT_FALSE(r.passed) << r.message;
}

TEST(Chi2Harness, SlightlyWrongExponentFails) {
  // cos^1.1 samples against the cosine pdf: chi-square divergence 0.0023 (integral of (p - q)^2 / q), so
  // ~2300 above the ~1600 dof at 1M samples, against a standard deviation of ~110.
  const Chi2Result r = chi2_test(power_cosine_sampler(1.1), cosine_pdf, options_for_file());
  EXPECT_FALSE(r.passed) << r.message;
}

TEST(Chi2Harness, WorstCellIsReported) {
  // 1% of the samples are moved into one cell (cos(theta) in [0.5, 0.55], phi < 4.5 deg); it must head the list.
  const auto sample = [](const Vec2& u) -> std::optional<Vec3> {
    if (u.x < 0.01f) {
      const float z = 0.525f, phi = 0.02f;
      const float r = std::sqrt(1 - z * z);
      return Vec3(r * std::cos(phi), r * std::sin(phi), z);
    }
    return warp::square_to_uniform_sphere(Vec2((u.x - 0.01f) / 0.99f, u.y));
  };
  const Chi2Result r = chi2_test(sample, uniform_sphere_pdf, options_for_file());
  ASSERT_FALSE(r.passed);
  const size_t list = r.message.find("worst cells");
  ASSERT_NE(list, std::string::npos) << r.message;
  EXPECT_NE(r.message.find("cos(theta) in [0.5000, 0.5500]", list), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("phi 0.00..4.50 deg", list), std::string::npos) << r.message;
}

TEST(Chi2Harness, NonUnitDirectionFails) {
  const auto sample = [](const Vec2& u) -> std::optional<Vec3> { return 1.01f * warp::square_to_uniform_sphere(u); };
  const Chi2Result r = chi2_test(sample, uniform_sphere_pdf, options_for_file());
  EXPECT_FALSE(r.passed);
  EXPECT_NE(r.message.find("not unit length"), std::string::npos) << r.message;
}

TEST(Chi2Harness, NonFiniteDirectionFails) {
  const auto sample = [](const Vec2& u) -> std::optional<Vec3> {
    if (u.x < 1e-4f) return Vec3(std::numeric_limits<float>::quiet_NaN());
    return warp::square_to_uniform_sphere(u);
  };
  const Chi2Result r = chi2_test(sample, uniform_sphere_pdf, options_for_file());
  EXPECT_FALSE(r.passed);
  EXPECT_NE(r.message.find("non-finite"), std::string::npos) << r.message;
}

TEST(Chi2Harness, NegativePdfFails) {
  const Chi2Result r = chi2_test(
      uniform_sphere, [](const Vec3& w) { return w.x / std::numbers::pi; }, options_for_file());
  EXPECT_FALSE(r.passed);
  EXPECT_NE(r.message.find("pdf returned"), std::string::npos) << r.message;
}

TEST(Chi2Harness, PlanarWrongPdfFails) {
  // Uniform points against the density 2x (the chi-square divergence is infinite), and points off the grid.
  const auto uniform = [](const Vec2& u) -> std::optional<Vec2> { return u; };
  const Chi2Result r = chi2_test_2d(uniform, linear_pdf, {}, options_for_file());
  EXPECT_FALSE(r.passed) << r.message;
  const Chi2Result outside = chi2_test_2d([](const Vec2& u) -> std::optional<Vec2> { return 1.5f * u; },
                                          [](const Vec2&) { return 1.0; }, {}, options_for_file());
  EXPECT_FALSE(outside.passed);
  EXPECT_NE(outside.message.find("outside the grid"), std::string::npos) << outside.message;
}

}  // namespace
}  // namespace kozu::test
