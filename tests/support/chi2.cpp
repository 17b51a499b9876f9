// Chi-square goodness-of-fit harness (see chi2.h): binning, numerical integration of the claimed pdf,
// pooling of small cells, Pearson's statistic and its p-value.
#include "support/chi2.h"

#include "core/rng.h"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>
#include <vector>

namespace kozu::test {
namespace {

constexpr double kPiD = 3.14159265358979323846;
constexpr double kRadToDeg = 180.0 / kPiD;
constexpr double kEpsilon = std::numeric_limits<double>::epsilon();

std::string format_point(const Vec2& p) { return fmt::format("({:.9g}, {:.9g})", p.x, p.y); }
std::string format_point(const Vec3& p) { return fmt::format("({:.9g}, {:.9g}, {:.9g})", p.x, p.y, p.z); }

// Evaluates the pdf, remembering the first invalid (negative or non-finite) value for the failure message.
template <typename Pdf, typename Point>
double checked_pdf(const Pdf& pdf, const Point& p, std::string* error) {
  const double value = pdf(p);
  if (!(value >= 0.0 && std::isfinite(value))) {
    if (error->empty()) *error = fmt::format("pdf returned {} at {}", value, format_point(p));
    return 0.0;
  }
  return value;
}

// Integral of pdf over the band cos(theta) in [z0, z1] split into nz x nphi cells, in (z, phi) coordinates
// where the solid angle is dz dphi. Fills per-cell integrals (row-major in z) when cells is given.
double integrate_band(const DirectionPdf& pdf, const GaussRule& rule, double z0, double z1, int nz, int nphi,
                      std::vector<double>* cells, std::string* error) {
  const int n = static_cast<int>(rule.x.size());
  const double dz = (z1 - z0) / nz, dphi = 2.0 * kPiD / nphi;
  // sin/cos of the phi nodes are shared by all rows.
  std::vector<double> cos_phi(static_cast<size_t>(nphi) * n), sin_phi(cos_phi.size());
  for (int ip = 0; ip < nphi; ++ip)
    for (int k = 0; k < n; ++k) {
      const double phi = (ip + 0.5 * (rule.x[k] + 1.0)) * dphi;
      cos_phi[static_cast<size_t>(ip) * n + k] = std::cos(phi);
      sin_phi[static_cast<size_t>(ip) * n + k] = std::sin(phi);
    }
  if (cells) cells->assign(static_cast<size_t>(nz) * nphi, 0.0);
  double total = 0;
  for (int iz = 0; iz < nz; ++iz) {
    for (int ip = 0; ip < nphi; ++ip) {
      double sum = 0;
      for (int j = 0; j < n; ++j) {
        const double z = z0 + (iz + 0.5 * (rule.x[j] + 1.0)) * dz;
        const double sin_t = std::sqrt(std::max(0.0, 1.0 - z * z));
        for (int k = 0; k < n; ++k) {
          const size_t node = static_cast<size_t>(ip) * n + k;
          const Vec3 w(static_cast<float>(sin_t * cos_phi[node]), static_cast<float>(sin_t * sin_phi[node]),
                       static_cast<float>(z));
          sum += rule.w[j] * rule.w[k] * checked_pdf(pdf, w, error);
        }
      }
      const double integral = sum * 0.25 * dz * dphi;
      if (cells) (*cells)[static_cast<size_t>(iz) * nphi + ip] = integral;
      total += integral;
    }
  }
  return total;
}

// Regularised lower incomplete gamma P(a, x) by its power series; converges quickly for x < a + 1.
// Numerical Recipes (3rd ed.) §6.2, gser.
double gamma_p_series(double a, double x) {
  double ap = a, term = 1.0 / a, sum = term;
  for (int n = 0; n < 1'000'000; ++n) {
    ap += 1.0;
    term *= x / ap;
    sum += term;
    if (std::abs(term) < std::abs(sum) * kEpsilon) return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
  }
  return std::numeric_limits<double>::quiet_NaN();
}

// Regularised upper incomplete gamma Q(a, x) by its continued fraction, evaluated with the modified Lentz
// method; converges quickly for x >= a + 1. Numerical Recipes (3rd ed.) §6.2, gcf.
double gamma_q_continued_fraction(double a, double x) {
  constexpr double kTiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / kTiny, d = 1.0 / b, h = d;
  for (int i = 1; i < 1'000'000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) <= kEpsilon) return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

double gamma_q(double a, double x) {
  if (x <= 0.0) return 1.0;
  return x < a + 1.0 ? 1.0 - gamma_p_series(a, x) : gamma_q_continued_fraction(a, x);
}

// Šidák: each of m independent tests at this level keeps the family-wise false-failure rate at significance.
double sidak_threshold(double significance, int test_count) {
  return -std::expm1(std::log1p(-significance) / std::max(test_count, 1));
}

std::string default_label(size_t cell) { return fmt::format("cell {}", cell); }

Chi2Result failure(Chi2Result result, std::string message) {
  result.passed = false;
  result.message = std::move(message);
  return result;
}

// The shared core: pooling, statistic, p-value and the message. context is appended to the summary line.
Chi2Result pearson(std::span<const double> observed, std::span<const double> expected, const Chi2Options& options,
                   const CellLabel& label_fn, Chi2Result result, const std::string& context) {
  const CellLabel label = label_fn ? label_fn : CellLabel(default_label);
  result.threshold = sidak_threshold(options.significance, options.test_count);
  const size_t n = observed.size();
  if (expected.size() != n)
    return failure(result, fmt::format("{} observed counts but {} expected", n, expected.size()));
  for (size_t i = 0; i < n; ++i) {
    if (!(expected[i] >= 0.0 && std::isfinite(expected[i])) || !(observed[i] >= 0.0 && std::isfinite(observed[i])))
      return failure(result,
                     fmt::format("invalid count in {}: observed {}, expected {}", label(i), observed[i], expected[i]));
    if (expected[i] == 0.0 && observed[i] > 0.0)
      return failure(result,
                     fmt::format("{} sample(s) in a region with pdf 0, {}; {}", observed[i], label(i), context));
  }

  // Pool cells in order of increasing expected count until the pool expects at least min_expected
  // (as Mitsuba's harness does), so that the chi-square approximation holds for every cell tested.
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return expected[a] < expected[b]; });
  std::vector<bool> pooled(n, false);
  double statistic = 0, pooled_observed = 0, pooled_expected = 0;
  int cells = 0, pooled_count = 0;
  for (size_t i : order) {
    if (expected[i] < options.min_expected || (pooled_expected > 0.0 && pooled_expected < options.min_expected)) {
      pooled_observed += observed[i];
      pooled_expected += expected[i];
      pooled[i] = true;
      ++pooled_count;
    } else {
      statistic += sqr(observed[i] - expected[i]) / expected[i];
      ++cells;
    }
  }
  if (pooled_expected > 0.0) {
    statistic += sqr(pooled_observed - pooled_expected) / pooled_expected;
    ++cells;
  }
  result.statistic = statistic;
  result.degrees_of_freedom = cells - 1;
  if (result.degrees_of_freedom < 1)
    return failure(result, fmt::format("only {} cell(s) after pooling: the test has no power (more samples or fewer "
                                       "bins needed); {}",
                                       cells, context));
  result.p_value = chi2_survival(statistic, result.degrees_of_freedom);
  result.passed = result.p_value >= result.threshold;

  result.message =
      fmt::format("chi2 = {:.2f}, dof = {}, p = {:.4g} (passes at >= {:.3g}), {} of {} cells pooled; {}", statistic,
                  result.degrees_of_freedom, result.p_value, result.threshold, pooled_count, n, context);
  if (!result.passed) {
    // The worst individual cells, pooled or not: a tiny cell with many samples is the usual culprit.
    std::vector<size_t> worst;
    for (size_t i = 0; i < n; ++i)
      if (expected[i] > 0.0) worst.push_back(i);
    const auto contribution = [&](size_t i) { return sqr(observed[i] - expected[i]) / expected[i]; };
    const size_t shown = std::min<size_t>(5, worst.size());
    std::partial_sort(worst.begin(), worst.begin() + shown, worst.end(),
                      [&](size_t a, size_t b) { return contribution(a) > contribution(b); });
    result.message += "\n  worst cells, by (O-E)^2/E:";
    for (size_t k = 0; k < shown; ++k) {
      const size_t i = worst[k];
      result.message += fmt::format("\n    {}: observed {}, expected {:.2f}, (O-E)^2/E = {:.2f}{}", label(i),
                                    observed[i], expected[i], contribution(i), pooled[i] ? " (pooled)" : "");
    }
    if (pooled_count > 0)
      result.message += fmt::format("\n    pool of {} cells: observed {}, expected {:.2f}", pooled_count,
                                    pooled_observed, pooled_expected);
  }
  return result;
}

Chi2Result validate(const Chi2Options& options, Chi2Result result) {
  if (options.sample_count <= 0 || options.integration_points <= 0 || options.min_expected <= 0 ||
      !(options.significance > 0 && options.significance < 1) || options.test_count < 1)
    return failure(result, fmt::format("invalid options: sample_count = {}, integration_points = {}, min_expected = "
                                       "{}, significance = {}, test_count = {}",
                                       options.sample_count, options.integration_points, options.min_expected,
                                       options.significance, options.test_count));
  result.passed = true;
  return result;
}

}  // namespace

GaussRule gauss_legendre(int n) {
  GaussRule rule{std::vector<double>(n), std::vector<double>(n)};
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double z = std::cos(kPiD * (i + 0.75) / (n + 0.5));
    double dp = 0;
    for (int iteration = 0; iteration < 100; ++iteration) {
      double p1 = 1, p2 = 0;
      for (int j = 0; j < n; ++j) {
        const double p3 = p2;
        p2 = p1;
        p1 = ((2.0 * j + 1.0) * z * p2 - j * p3) / (j + 1.0);
      }
      dp = n * (z * p1 - p2) / (z * z - 1.0);
      const double dz = p1 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-15) break;
    }
    rule.x[i] = -z;
    rule.x[n - 1 - i] = z;
    rule.w[i] = rule.w[n - 1 - i] = 2.0 / ((1.0 - z * z) * dp * dp);
  }
  return rule;
}

double chi2_survival(double chi2, int dof) {
  if (dof < 1 || std::isnan(chi2)) return std::numeric_limits<double>::quiet_NaN();
  return std::clamp(gamma_q(0.5 * dof, 0.5 * chi2), 0.0, 1.0);
}

double integrate_pdf_over_sphere(const DirectionPdf& pdf, int resolution) {
  std::string error;
  const double integral =
      integrate_band(pdf, gauss_legendre(8), -1.0, 1.0, resolution, 2 * resolution, nullptr, &error);
  return error.empty() ? integral : std::numeric_limits<double>::quiet_NaN();
}

Chi2Result chi2_test_counts(std::span<const double> observed, std::span<const double> expected,
                            const Chi2Options& options, const CellLabel& label) {
  Chi2Result result = validate(options, {});
  if (!result.passed) return result;
  const double total_observed = std::accumulate(observed.begin(), observed.end(), 0.0);
  const double total_expected = std::accumulate(expected.begin(), expected.end(), 0.0);
  return pearson(observed, expected, options, label, result,
                 fmt::format("observed total = {}, expected total = {:.2f}", total_observed, total_expected));
}

Chi2Result chi2_test(const DirectionSampler& sample, const DirectionPdf& pdf, const Chi2Options& options) {
  Chi2Result result = validate(options, {});
  if (!result.passed) return result;
  const double z0 = options.cos_theta_min, z1 = options.cos_theta_max;
  const int nz = options.theta_bins, nphi = options.phi_bins;
  if (nz < 1 || nphi < 1 || !(-1.0 <= z0 && z0 < z1 && z1 <= 1.0))
    return failure(result,
                   fmt::format("invalid sphere layout: {} x {} bins over cos(theta) in [{}, {}]", nz, nphi, z0, z1));
  const size_t grid_cells = static_cast<size_t>(nz) * nphi;
  const size_t outside_cell = grid_cells, lost_cell = grid_cells + 1;

  std::vector<double> observed(grid_cells + 2, 0.0);
  Pcg32 rng(options.seed);
  for (int s = 0; s < options.sample_count; ++s) {
    const Vec2 u(rng.next_float(), rng.next_float());
    const std::optional<Vec3> w = sample(u);
    if (!w) {
      ++observed[lost_cell];
      continue;
    }
    if (!is_finite(*w))
      return failure(result, fmt::format("sample(u = {}) returned a non-finite direction ({}, {}, {})", format_point(u),
                                         w->x, w->y, w->z));
    const double length = glm::length(glm::dvec3(*w));
    if (std::abs(length - 1.0) > 1e-3)
      return failure(result, fmt::format("sample(u = {}) returned a direction that is not unit length: ({}, {}, {}), "
                                         "|w| = {}",
                                         format_point(u), w->x, w->y, w->z, length));
    const double z = std::clamp(static_cast<double>(w->z), -1.0, 1.0);
    if (z < z0 || z > z1) {
      ++observed[outside_cell];
      continue;
    }
    double phi = std::atan2(static_cast<double>(w->y), static_cast<double>(w->x));
    if (phi < 0.0) phi += 2.0 * kPiD;
    const int iz = std::min(static_cast<int>((z - z0) / (z1 - z0) * nz), nz - 1);
    const int ip = std::min(static_cast<int>(phi / (2.0 * kPiD) * nphi), nphi - 1);
    ++observed[static_cast<size_t>(iz) * nphi + ip];
  }

  std::string error;
  const GaussRule rule = gauss_legendre(options.integration_points);
  std::vector<double> expected;
  const double inside = integrate_band(pdf, rule, z0, z1, nz, nphi, &expected, &error);
  double outside = 0;
  if (z0 > -1.0) outside += integrate_band(pdf, rule, -1.0, z0, nz, nphi, nullptr, &error);
  if (z1 < 1.0) outside += integrate_band(pdf, rule, z1, 1.0, nz, nphi, nullptr, &error);
  if (!error.empty()) return failure(result, error);
  result.pdf_integral = inside + outside;
  result.lost_samples = static_cast<int64_t>(observed[lost_cell]);

  // The grid, then the rest of the sphere (if the grid does not cover it), then the rejected samples.
  const double count = options.sample_count;
  const double outside_observed = observed[outside_cell], lost_observed = observed[lost_cell];
  const bool has_outside = z0 > -1.0 || z1 < 1.0;
  observed.resize(grid_cells);
  for (double& e : expected) e *= count;
  if (has_outside) {
    observed.push_back(outside_observed);
    expected.push_back(outside * count);
  }
  if (options.check_lost_mass) {
    observed.push_back(lost_observed);
    expected.push_back(count * std::max(0.0, 1.0 - result.pdf_integral));
  }

  const CellLabel label = [&](size_t i) -> std::string {
    if (i >= grid_cells) {
      if (has_outside && i == grid_cells) return fmt::format("outside the binned range cos(theta) in [{}, {}]", z0, z1);
      return "the rejected samples (nullopt), expected to number N * (1 - pdf integral)";
    }
    const int iz = static_cast<int>(i) / nphi, ip = static_cast<int>(i) % nphi;
    const double c0 = z0 + (z1 - z0) * iz / nz, c1 = z0 + (z1 - z0) * (iz + 1) / nz;
    return fmt::format("cos(theta) in [{:.4f}, {:.4f}] (theta {:.2f}..{:.2f} deg), phi {:.2f}..{:.2f} deg", c0, c1,
                       std::acos(c1) * kRadToDeg, std::acos(c0) * kRadToDeg, 360.0 * ip / nphi,
                       360.0 * (ip + 1) / nphi);
  };
  const std::string context = fmt::format(
      "pdf integral = {:.6f}, {} samples ({} rejected{})", result.pdf_integral, options.sample_count,
      result.lost_samples, has_outside ? fmt::format(", {} outside the binned range", outside_observed) : "");
  return pearson(observed, expected, options, label, result, context);
}

Chi2Result chi2_test_2d(const PointSampler& sample, const PointPdf& pdf, const Chi2Grid2D& grid,
                        const Chi2Options& options) {
  Chi2Result result = validate(options, {});
  if (!result.passed) return result;
  const int nx = grid.x_bins, ny = grid.y_bins;
  if (nx < 1 || ny < 1 || !(grid.x0 < grid.x1 && grid.y0 < grid.y1))
    return failure(result, fmt::format("invalid grid: {} x {} bins over [{}, {}] x [{}, {}]", nx, ny, grid.x0, grid.x1,
                                       grid.y0, grid.y1));
  const size_t grid_cells = static_cast<size_t>(nx) * ny, lost_cell = grid_cells;
  const double dx = (grid.x1 - grid.x0) / nx, dy = (grid.y1 - grid.y0) / ny;

  std::vector<double> observed(grid_cells + 1, 0.0);
  Pcg32 rng(options.seed);
  for (int s = 0; s < options.sample_count; ++s) {
    const Vec2 u(rng.next_float(), rng.next_float());
    const std::optional<Vec2> p = sample(u);
    if (!p) {
      ++observed[lost_cell];
      continue;
    }
    if (!std::isfinite(p->x) || !std::isfinite(p->y))
      return failure(result,
                     fmt::format("sample(u = {}) returned a non-finite point ({}, {})", format_point(u), p->x, p->y));
    const double x = p->x, y = p->y;
    if (x < grid.x0 || x > grid.x1 || y < grid.y0 || y > grid.y1)
      return failure(result,
                     fmt::format("sample(u = {}) returned ({:.9g}, {:.9g}), outside the grid [{}, {}] x [{}, {}]",
                                 format_point(u), x, y, grid.x0, grid.x1, grid.y0, grid.y1));
    const int ix = std::min(static_cast<int>((x - grid.x0) / dx), nx - 1);
    const int iy = std::min(static_cast<int>((y - grid.y0) / dy), ny - 1);
    ++observed[static_cast<size_t>(iy) * nx + ix];
  }

  std::string error;
  const GaussRule rule = gauss_legendre(options.integration_points);
  const int n = options.integration_points;
  std::vector<double> expected(grid_cells + 1, 0.0);
  double integral = 0;
  for (int iy = 0; iy < ny; ++iy)
    for (int ix = 0; ix < nx; ++ix) {
      double sum = 0;
      for (int j = 0; j < n; ++j)
        for (int k = 0; k < n; ++k) {
          const Vec2 p(static_cast<float>(grid.x0 + (ix + 0.5 * (rule.x[k] + 1.0)) * dx),
                       static_cast<float>(grid.y0 + (iy + 0.5 * (rule.x[j] + 1.0)) * dy));
          sum += rule.w[j] * rule.w[k] * checked_pdf(pdf, p, &error);
        }
      const double cell = sum * 0.25 * dx * dy;
      expected[static_cast<size_t>(iy) * nx + ix] = cell * options.sample_count;
      integral += cell;
    }
  if (!error.empty()) return failure(result, error);
  result.pdf_integral = integral;
  result.lost_samples = static_cast<int64_t>(observed[lost_cell]);
  expected[lost_cell] = options.sample_count * std::max(0.0, 1.0 - integral);
  if (!options.check_lost_mass) {
    observed.pop_back();
    expected.pop_back();
  }

  const CellLabel label = [&](size_t i) -> std::string {
    if (i == lost_cell) return "the rejected samples (nullopt), expected to number N * (1 - pdf integral)";
    const int ix = static_cast<int>(i) % nx, iy = static_cast<int>(i) / nx;
    return fmt::format("x in [{:.4g}, {:.4g}], y in [{:.4g}, {:.4g}]", grid.x0 + ix * dx, grid.x0 + (ix + 1) * dx,
                       grid.y0 + iy * dy, grid.y0 + (iy + 1) * dy);
  };
  const std::string context = fmt::format("pdf integral = {:.6f}, {} samples ({} rejected)", integral,
                                          options.sample_count, result.lost_samples);
  return pearson(observed, expected, options, label, result, context);
}

}  // namespace kozu::test
