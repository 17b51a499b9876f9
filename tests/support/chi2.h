// Chi-square goodness-of-fit tests for sampling routines: run a sampler many times, bin its samples,
// and compare the counts with the pdf it claims, integrated numerically over each bin.
//   chi2_test         directions on the sphere, binned in (cos theta, phi)
//   chi2_test_2d      points in a rectangle
//   chi2_test_counts  the shared core (pooling, statistic, p-value) for any histogram, e.g. discrete pmfs
// The statistical model follows Mitsuba's harness (Jakob et al.): Pearson's statistic, small cells pooled,
// p-value from the chi-square distribution, Šidák correction for a family of tests.
#pragma once

#include "core/math.h"

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace kozu::test {

struct Chi2Options {
  // Sphere layout (chi2_test): theta_bins cells uniform in cos(theta) over [cos_theta_min, cos_theta_max] and
  // phi_bins uniform in phi over [0, 2pi), so all cells have equal solid angle. Narrowing the cos(theta)
  // range concentrates the bins on a sampler's support (e.g. a narrow cone); the rest of the sphere is one
  // extra "outside" cell whose expected count is the pdf integrated there.
  int theta_bins = 40;
  int phi_bins = 80;  // 2:1 in phi / theta
  double cos_theta_min = -1.0;
  double cos_theta_max = 1.0;
  int sample_count = 1'000'000;
  // Gauss–Legendre points per cell and dimension for the expected counts. Exact for smooth pdfs; a pdf
  // discontinuity inside a cell is only resolved to O(1/points), so put discontinuities on cell edges.
  int integration_points = 8;
  double min_expected = 5.0;   // cells expecting fewer samples are pooled
  double significance = 0.01;  // for the whole family of tests, before the Šidák correction
  int test_count = 1;          // number of tests in the family, for the Šidák correction
  uint64_t seed = 1;
  // Treat rejected samples (nullopt) as one more cell expecting sample_count * (1 - pdf integral). This
  // catches pdfs that are misnormalised by far less than the cells alone can, but needs the numerical
  // integral accurate to ~1e-5; switch it off for pdfs the quadrature cannot resolve.
  bool check_lost_mass = true;
};

struct Chi2Result {
  bool passed = false;
  double statistic = 0;
  int degrees_of_freedom = 0;
  double p_value = 0;
  double threshold = 0;      // smallest passing p-value, after the Šidák correction
  double pdf_integral = 0;   // integral of pdf over the whole domain (should be <= 1)
  int64_t lost_samples = 0;  // samples the sampler rejected (nullopt)
  std::string message;       // one-line summary, plus the worst cells on failure
};

// sample(u) returns a unit direction, or nullopt when the sampler rejects (mass lost).
// pdf(w) is the solid-angle density the sampler claims.
using DirectionSampler = std::function<std::optional<Vec3>(const Vec2& u)>;
using DirectionPdf = std::function<double(const Vec3& w)>;

// Draws options.sample_count directions from u = (next_float, next_float) of Pcg32(options.seed), bins them and
// compares the counts with sample_count * (pdf integrated over each cell). Fails outright on a non-finite or
// non-unit (| |w| - 1 | > 1e-3) direction, a negative or non-finite pdf value, or samples in a cell where the pdf
// integrates to 0. Passes when p >= 1 - (1 - significance)^(1 / test_count).
Chi2Result chi2_test(const DirectionSampler& sample, const DirectionPdf& pdf, const Chi2Options& options = {});

// A rectangle [x0, x1) x [y0, y1) split into x_bins x y_bins equal cells.
struct Chi2Grid2D {
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  int x_bins = 40, y_bins = 40;
};

// sample(u) returns a point, or nullopt when it rejects; pdf(p) is the claimed density per unit area.
// A point outside the grid fails the test: express the domain so that the grid covers the support.
using PointSampler = std::function<std::optional<Vec2>(const Vec2& u)>;
using PointPdf = std::function<double(const Vec2& p)>;

// Same test on a rectangle; options' theta/phi fields are unused.
Chi2Result chi2_test_2d(const PointSampler& sample, const PointPdf& pdf, const Chi2Grid2D& grid,
                        const Chi2Options& options = {});

// Names cell i in failure messages.
using CellLabel = std::function<std::string(size_t cell)>;

// Pearson's test of observed against expected counts, pooling cells that expect fewer than
// options.min_expected; only min_expected, significance and test_count are used from options.
// A cell that expects 0 but received samples fails outright.
Chi2Result chi2_test_counts(std::span<const double> observed, std::span<const double> expected,
                            const Chi2Options& options = {}, const CellLabel& label = {});

// P(X >= chi2) for X chi-square distributed with dof degrees of freedom.
double chi2_survival(double chi2, int dof);

// Gauss–Legendre nodes and weights on [-1, 1] by Newton iteration on P_n (Numerical Recipes §4.6, gauleg).
struct GaussRule {
  std::vector<double> x, w;
};
GaussRule gauss_legendre(int n);

// Integral of pdf over the sphere on a grid of resolution cells in cos(theta) by 2 * resolution in phi, each
// with an 8 x 8 Gauss–Legendre rule (exact for smooth pdfs; discontinuities should lie on cell edges).
double integrate_pdf_over_sphere(const DirectionPdf& pdf, int resolution);

}  // namespace kozu::test
