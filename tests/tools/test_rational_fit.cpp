// Rational fitting (tools/rational_fit.h, `kozu fit-rational`) after D. Chan, "Material Advances in Call of Duty:
// WWII", SIGGRAPH 2018 course Advances in Real-Time Rendering in Games, §3: exact recovery of known rational
// functions (one variable, two, symmetric), constraints met exactly, poles refused, tables and flags checked, and the
// paper's own fits redone on tables computed here: the gloss → shortened-normal length curve (eq. 26, itself checked
// against numerical integration of the GGX NDF, as eq. 24 is) for eqs. (40) and (42), and the detail-gloss table
// of eq. (34) for eqs. (35)–(37).
#include "tools/rational_fit.h"

#include "core/error.h"

#include "apps/cli_helpers.h"
#include "support/render_test.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace kozu {
namespace {

using test::TempDir;

// Chan 2018 eq. (2): GGX α of a gloss.
double gloss_alpha(double g) { return std::sqrt(2.0 / (1.0 + std::exp2(18.0 * g))); }

// Chan 2018 eq. (26) (macrosurface shortened-normal length), a = √(1 − α²) (eq. 27); near a = 0 the closed form
// cancels (a − (1 − a²) atanh a ~ 2a³/3), so there the series 2 Σ_k a^(2k−2) / ((2k − 1)(2k + 1)) is summed.
double macro_length(double alpha) {
  const double a = std::sqrt(std::max(1.0 - alpha * alpha, 0.0));
  if (a < 0.2) {
    double s = 0, p = 1;
    for (int k = 1; k < 40; ++k, p *= a * a) s += 2.0 * p / ((2.0 * k - 1) * (2.0 * k + 1));
    return s;
  }
  return (a - (1 - a * a) * std::atanh(a)) / (a * a * a);
}
// Chan 2018 eq. (24) (microsurface).
double micro_length(double alpha) {
  const double a = std::sqrt(std::max(1.0 - alpha * alpha, 0.0));
  return a < 1e-8 ? 0.5 : a / (a + (1 - a * a) * std::atanh(a));
}
double gloss_to_length(double g) { return macro_length(gloss_alpha(g)); }
// The inverse of gloss_to_length, by bisection (the length rises with gloss); 0 below the length at gloss 0.
double length_to_gloss(double l) {
  if (l <= gloss_to_length(0)) return 0;
  if (l >= gloss_to_length(1)) return 1;
  double lo = 0, hi = 1;
  for (int i = 0; i < 100; ++i) (gloss_to_length(0.5 * (lo + hi)) < l ? lo : hi) = 0.5 * (lo + hi);
  return 0.5 * (lo + hi);
}

// 2π ∫ D(θ) w(θ) sin θ dθ over the hemisphere for the GGX NDF, by composite Simpson on panels graded around the
// peak's width α (breakpoints at atan(α 2^k)), so that tiny α is integrated as well as large.
template <class W>
double integrate_ggx(double alpha, W weight) {
  const double a2 = alpha * alpha;
  const auto d = [&](double t) {
    const double c = std::cos(t), tan2 = std::tan(t) * std::tan(t);
    return a2 / (std::numbers::pi * c * c * c * c * (a2 + tan2) * (a2 + tan2));
  };
  std::vector<double> cuts{0};
  for (int k = -12; k <= 24; ++k) {
    const double t = std::atan(alpha * std::exp2(k));
    if (t > cuts.back() && t < std::numbers::pi / 2) cuts.push_back(t);
  }
  cuts.push_back(std::numbers::pi / 2);
  double sum = 0;
  for (size_t p = 0; p + 1 < cuts.size(); ++p) {
    const int n = 256;
    const double h = (cuts[p + 1] - cuts[p]) / n;
    const auto f = [&](double t) { return t >= std::numbers::pi / 2 ? 0.0 : d(t) * weight(t) * std::sin(t); };
    double s = f(cuts[p]) + f(cuts[p + 1]);
    for (int i = 1; i < n; ++i) s += (i % 2 ? 4 : 2) * f(cuts[p] + i * h);
    sum += s * h / 3;
  }
  return 2 * std::numbers::pi * sum;
}

struct Errors {
  double max = 0, mean = 0, rms = 0;
};
template <class F>
Errors errors_of(const std::vector<RationalSample>& table, F f) {
  Errors e;
  for (const RationalSample& s : table) {
    const double d = std::fabs(f(s.x, s.y) - s.value);
    e.max = std::max(e.max, d);
    e.mean += d / double(table.size());
    e.rms += d * d / double(table.size());
  }
  e.rms = std::sqrt(e.rms);
  return e;
}

double poly1(const std::vector<double>& c, double x) {
  double s = 0;
  for (size_t i = c.size(); i-- > 0;) s = s * x + c[i];
  return s;
}
// Eqs. (35)–(36): c0 + c1 (a + b) + c2 (a² + b²) + c3 ab.
double sym2(const std::vector<double>& c, double a, double b) {
  return c[0] + c[1] * (a + b) + c[2] * (a * a + b * b) + c[3] * a * b;
}

TEST(RationalFit, TermOrder) {
  using P = std::vector<std::pair<int, int>>;
  EXPECT_EQ(rational_terms(RationalBasis::OneD, 3), (P{{0, 0}, {1, 0}, {2, 0}, {3, 0}}));
  EXPECT_EQ(rational_terms(RationalBasis::TwoD, 2), (P{{0, 0}, {1, 0}, {0, 1}, {2, 0}, {1, 1}, {0, 2}}));
  // The order of eqs. (35)–(36): 1, a + b, a² + b², ab.
  EXPECT_EQ(rational_terms(RationalBasis::TwoDSymmetric, 2), (P{{0, 0}, {1, 0}, {2, 0}, {1, 1}}));
  EXPECT_EQ(rational_terms(RationalBasis::TwoDSymmetric, 3).size(), 6u);
  EXPECT_EQ(rational_term_name(RationalBasis::TwoDSymmetric, 2, 1), "x^2*y + x*y^2");
  EXPECT_EQ(rational_term_name(RationalBasis::TwoDSymmetric, 1, 1), "x*y");
  EXPECT_EQ(rational_term_name(RationalBasis::TwoD, 0, 0), "1");
}

TEST(RationalFit, RecoversAKnownFunction) {
  const std::vector<double> p{0.5, 2.0, -1.0, 0.3}, q{1.0, 0.7, 0.2};
  std::vector<RationalSample> table;
  for (int i = 0; i <= 50; ++i) table.push_back({2.0 * i / 50, 0, poly1(p, 2.0 * i / 50) / poly1(q, 2.0 * i / 50)});
  for (const bool refine : {false, true}) {
    RationalFitOptions o;
    o.num_degree = 3;
    o.den_degree = 2;
    o.refine = refine;
    const RationalFit f = fit_rational(table, o);
    ASSERT_EQ(f.numerator.size(), 4u);
    ASSERT_EQ(f.denominator.size(), 3u);
    EXPECT_EQ(f.denominator[0], 1.0);
    for (size_t i = 0; i < 4; ++i) EXPECT_NEAR(f.numerator[i], p[i], 1e-10) << i;
    for (size_t i = 0; i < 3; ++i) EXPECT_NEAR(f.denominator[i], q[i], 1e-10) << i;
    EXPECT_LT(f.max_abs_error, 1e-12);
  }
}

TEST(RationalFit, RecoversTwoVariables) {
  // Symmetric (eqs. 35–36) and general forms, each from noiseless samples on a 9 × 9 grid.
  const std::vector<double> p{0.2, 0.5, 0.1, 0.7}, q{1.0, 0.3, 0.2, -0.1};
  std::vector<RationalSample> table;
  for (int i = 0; i < 9; ++i)
    for (int j = 0; j < 9; ++j)
      table.push_back({i / 8.0, j / 8.0, sym2(p, i / 8.0, j / 8.0) / sym2(q, i / 8.0, j / 8.0)});
  RationalFitOptions o;
  o.basis = RationalBasis::TwoDSymmetric;
  o.num_degree = o.den_degree = 2;
  RationalFit f = fit_rational(table, o);
  for (size_t i = 0; i < 4; ++i) EXPECT_NEAR(f.numerator[i], p[i], 1e-10) << i;
  for (size_t i = 0; i < 4; ++i) EXPECT_NEAR(f.denominator[i], q[i], 1e-10) << i;
  EXPECT_LT(f.max_abs_error, 1e-12);

  // General: 1, x, y, x², xy, y² over 1, x, y.
  const auto g = [](double x, double y) {
    return (0.1 + 0.4 * x - 0.3 * y + 0.2 * x * x + 0.5 * x * y + 0.05 * y * y) / (1 + 0.6 * x + 0.25 * y);
  };
  table.clear();
  for (int i = 0; i < 9; ++i)
    for (int j = 0; j < 9; ++j) table.push_back({i / 8.0, j / 8.0, g(i / 8.0, j / 8.0)});
  o.basis = RationalBasis::TwoD;
  o.num_degree = 2;
  o.den_degree = 1;
  f = fit_rational(table, o);
  const std::vector<double> pn{0.1, 0.4, -0.3, 0.2, 0.5, 0.05}, qn{1, 0.6, 0.25};
  for (size_t i = 0; i < pn.size(); ++i) EXPECT_NEAR(f.numerator[i], pn[i], 1e-10) << i;
  for (size_t i = 0; i < qn.size(); ++i) EXPECT_NEAR(f.denominator[i], qn[i], 1e-10) << i;
  EXPECT_NEAR(rational_eval(RationalBasis::TwoD, f.numerator, f.denominator, 0.3, 0.7), g(0.3, 0.7), 1e-12);
}

// Eq. (63)'s form, 1, x, y, x², y², xy, x³, y³ over the same, as explicit terms: its own coefficients recovered from
// noiseless samples; and the term lists' parser.
TEST(RationalFit, RecoversEq63sForm) {
  const std::vector<double> p{0.568, -0.692, -0.938, 1.326, 0.301, 1.96, -0.98, 1.533};
  const std::vector<double> q{1.0, 1.731, -0.997, -0.998, -0.843, 9.905, -0.971, 0.948};
  const auto terms = parse_rational_terms("1, x, y, x^2, y^2, x*y, x^3, y^3", RationalBasis::TwoD);
  ASSERT_EQ(terms, (std::vector<std::pair<int, int>>{{0, 0}, {1, 0}, {0, 1}, {2, 0}, {0, 2}, {1, 1}, {3, 0}, {0, 3}}));
  std::vector<RationalSample> table;
  for (int i = 0; i <= 10; ++i)
    for (int j = 0; j <= 10; ++j)
      table.push_back({i / 10.0, j / 10.0, rational_eval(RationalBasis::TwoD, terms, p, terms, q, i / 10.0, j / 10.0)});
  RationalFitOptions o;
  o.basis = RationalBasis::TwoD;
  o.num_terms = o.den_terms = terms;
  const RationalFit f = fit_rational(table, o);
  for (size_t i = 0; i < p.size(); ++i) EXPECT_NEAR(f.numerator[i], p[i], 1e-9) << i;
  for (size_t i = 0; i < q.size(); ++i) EXPECT_NEAR(f.denominator[i], q[i], 1e-9) << i;
  EXPECT_NEAR(f(0.35, 0.8), rational_eval(RationalBasis::TwoD, terms, p, terms, q, 0.35, 0.8), 1e-12);

  // The symmetric basis names a pair by either member; bad terms are refused with their text.
  EXPECT_EQ(parse_rational_terms("1,x*y^2", RationalBasis::TwoDSymmetric),
            (std::vector<std::pair<int, int>>{{0, 0}, {2, 1}}));
  for (const char* bad : {"1,z", "x^", "x^0", "x^21", "x,,y", "1,x,x", "y"})
    EXPECT_THROW(parse_rational_terms(bad, RationalBasis::OneD), std::invalid_argument) << bad;
  o.den_terms = {{1, 0}};  // no constant term
  EXPECT_THROW(fit_rational(table, o), std::invalid_argument);
}

TEST(RationalFit, ConstraintsAreMetExactly) {
  // A function no 2/2 rational matches, constrained at three points (one off the curve by 0.01, one outside the
  // data).
  const auto g = [](double x) { return std::exp(-x) * std::cos(x / 0.6); };
  std::vector<RationalSample> table;
  for (int i = 0; i <= 100; ++i) table.push_back({i / 50.0, 0, g(i / 50.0)});
  RationalFitOptions o;
  o.num_degree = 2;
  o.den_degree = 2;
  o.constraints = {{0.0, 0, 1.0}, {0.75, 0, g(0.75) + 0.01}, {2.5, 0, g(2.5)}};
  for (const bool minimax : {false, true}) {
    o.minimax = minimax;
    o.minimax_iterations = 30;
    const RationalFit f = fit_rational(table, o);
    for (const RationalSample& c : o.constraints)
      EXPECT_NEAR(rational_eval(RationalBasis::OneD, f.numerator, f.denominator, c.x), c.value, 1e-12) << c.x;
    EXPECT_LT(f.max_abs_error, 0.05);
  }
  // Two variables, symmetric.
  table.clear();
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j) table.push_back({i / 7.0, j / 7.0, std::exp(-(i + j) / 7.0) + 0.1 * i * j / 49.0});
  o = {};
  o.basis = RationalBasis::TwoDSymmetric;
  o.num_degree = o.den_degree = 2;
  o.constraints = {{0, 0, 1.0}, {1, 1, 0.25}};
  const RationalFit f = fit_rational(table, o);
  for (const RationalSample& c : o.constraints)
    EXPECT_NEAR(rational_eval(o.basis, f.numerator, f.denominator, c.x, c.y), c.value, 1e-12);
}

TEST(RationalFit, RefusesWhatCannotBeFitted) {
  std::vector<RationalSample> table;
  for (int i = 0; i < 10; ++i) table.push_back({i / 9.0, 0, i / 9.0});
  RationalFitOptions o;
  o.num_degree = 1;
  o.den_degree = 1;
  o.constraints = {{0.5, 0, 0.5}, {0.5, 0, 0.5}};  // the same twice: dependent
  EXPECT_THROW(fit_rational(table, o), std::invalid_argument);
  o.constraints = {};
  o.num_degree = 8;
  o.den_degree = 4;  // 12 unknowns, 10 samples
  EXPECT_THROW(fit_rational(table, o), std::invalid_argument);
  o.num_degree = 21;
  EXPECT_THROW(fit_rational(table, o), std::invalid_argument);

  // -2 / (1 − 2x) has a pole inside the data: the linearised solve finds it exactly and is refused; the refined fit
  // starts from the polynomial and never lets Q reach 0, so it is pole-free (and poor).
  table.clear();
  for (int i = 0; i <= 20; ++i)
    if (i != 10) table.push_back({i / 20.0, 0, -2 / (1 - 2 * (i / 20.0))});
  o.num_degree = 0;
  o.den_degree = 1;
  o.refine = false;
  EXPECT_THROW(fit_rational(table, o), std::invalid_argument);
  o.refine = true;
  const RationalFit f = fit_rational(table, o);
  for (int k = 0; k <= 100; ++k) EXPECT_GT(poly1(f.denominator, k / 100.0), 0) << k;
}

// Eqs. (24) and (26) against the integrals they close (eqs. 23, 25), for glosses across the range.
TEST(RationalFit, ShortenedNormalLengthsMatchTheGgxIntegrals) {
  for (const double g : {0.0, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0}) {
    const double alpha = gloss_alpha(g);
    const double norm = integrate_ggx(alpha, [](double t) { return std::cos(t); });  // ∫ D cos dω = 1
    EXPECT_NEAR(norm, 1.0, 1e-8) << g;
    // Macro (eq. 25): |∫ m D(m) (m·n) dm| = ∫ D cos² dω (the tangential parts cancel by symmetry).
    const double macro = integrate_ggx(alpha, [](double t) { return std::cos(t) * std::cos(t); });
    EXPECT_NEAR(macro_length(alpha), macro, 1e-8) << g;
    // Micro (eq. 23): 1 / ∫ D dω.
    const double micro = 1 / integrate_ggx(alpha, [](double) { return 1.0; });
    EXPECT_NEAR(micro_length(alpha), micro, 1e-8) << g;
  }
  // The series and the closed form agree where they meet.
  const double alpha = std::sqrt(1 - 0.2 * 0.2);
  EXPECT_NEAR(macro_length(alpha), macro_length(std::sqrt(1 - 0.20000001 * 0.20000001)), 1e-8);
  EXPECT_NEAR(macro_length(1.0), 2.0 / 3.0, 1e-15);
  EXPECT_NEAR(gloss_to_length(1.0), 0.999958, 1e-6);  // the paper's f(1)
}

std::vector<RationalSample> gloss_length_table() {
  std::vector<RationalSample> t;
  for (int i = 0; i < 256; ++i) t.push_back({i / 255.0, 0, gloss_to_length(i / 255.0)});
  return t;
}

// Eq. (40): the unconstrained 3/2 fit of the 256-entry gloss → length table reproduces the paper's coefficients,
// and fits the table at least as well as they do (least squares: in RMS; minimax: in the largest error).
TEST(RationalFit, PaperEq40) {
  const std::vector<RationalSample> table = gloss_length_table();
  const std::vector<double> pp{0.66693, 0.0609009, 7.32398, 0.600464}, pq{1.0, -1.13467, 8.78264};
  const Errors paper = errors_of(table, [&](double x, double) { return poly1(pp, x) / poly1(pq, x); });
  RationalFitOptions o;
  o.num_degree = 3;
  o.den_degree = 2;
  const RationalFit f = fit_rational(table, o);
  for (size_t i = 0; i < 4; ++i) EXPECT_NEAR(f.numerator[i], pp[i], 2e-3 * std::max(1.0, std::fabs(pp[i]))) << i;
  for (size_t i = 0; i < 3; ++i) EXPECT_NEAR(f.denominator[i], pq[i], 2e-3 * std::max(1.0, std::fabs(pq[i]))) << i;
  EXPECT_LE(f.rms_error, paper.rms);
  EXPECT_LE(f.max_abs_error, paper.max);  // 4.2e-4 against 5.4e-4
  o.minimax = true;
  o.minimax_iterations = 30;
  const RationalFit m = fit_rational(table, o);
  EXPECT_LE(m.max_abs_error, paper.max);
  EXPECT_LE(m.max_abs_error, f.max_abs_error);
}

// Eq. (42): the 3/2 fit with f(0) = 0.66667 and f(1) = 0.999958 (eq. 41). The printed coefficients meet neither
// exactly (c0 = 0.6667 is rounded; their f(1) is 0.9999612), so the least-squares comparison puts c0 back to
// 0.66667; the minimax fit, which meets both, has a smaller largest error than the printed coefficients.
TEST(RationalFit, PaperEq42) {
  const std::vector<RationalSample> table = gloss_length_table();
  std::vector<double> pp{0.6667, 0.0942205, 7.41935, 0.56711};
  const std::vector<double> pq{1.0, -1.0881, 8.83582};
  const Errors printed = errors_of(table, [&](double x, double) { return poly1(pp, x) / poly1(pq, x); });
  pp[0] = 0.66667;
  const Errors constrained = errors_of(table, [&](double x, double) { return poly1(pp, x) / poly1(pq, x); });
  RationalFitOptions o;
  o.num_degree = 3;
  o.den_degree = 2;
  o.constraints = {{0, 0, 0.66667}, {1, 0, 0.999958}};
  const RationalFit f = fit_rational(table, o);
  for (const RationalSample& c : o.constraints)
    EXPECT_NEAR(rational_eval(o.basis, f.numerator, f.denominator, c.x), c.value, 1e-12);
  for (size_t i = 1; i < 4; ++i) EXPECT_NEAR(f.numerator[i], pp[i], 1e-2 * std::max(1.0, std::fabs(pp[i]))) << i;
  for (size_t i = 0; i < 3; ++i) EXPECT_NEAR(f.denominator[i], pq[i], 1e-2 * std::max(1.0, std::fabs(pq[i]))) << i;
  EXPECT_LE(f.rms_error, constrained.rms);
  o.minimax = true;
  o.minimax_iterations = 30;
  const RationalFit m = fit_rational(table, o);
  for (const RationalSample& c : o.constraints)
    EXPECT_NEAR(rational_eval(o.basis, m.numerator, m.denominator, c.x), c.value, 1e-12);
  EXPECT_LE(m.max_abs_error, printed.max);  // 2.7e-4 against 3.15e-4
}

// Eqs. (35)–(37): the 32 × 32 detail-gloss table of eq. (34) (the gloss whose length is the product of two
// glosses' lengths), fitted symmetric 2/2 with the clamp of eq. (37).
TEST(RationalFit, PaperEq37) {
  std::vector<RationalSample> table;
  for (int i = 0; i < 32; ++i)
    for (int j = 0; j < 32; ++j)
      table.push_back({i / 31.0, j / 31.0, length_to_gloss(gloss_to_length(i / 31.0) * gloss_to_length(j / 31.0))});
  // Eq. (34) is symmetric, and a gloss of 1 barely shortens: the table's corner is the other gloss.
  EXPECT_NEAR(table[5 * 32 + 31].value, table[31 * 32 + 5].value, 1e-12);
  const std::vector<double> pp{-0.535580, 1.002204, -0.223910, 13.323150}, pq{1.0, 8.259559, 9.896132, -22.015902};
  const auto clamp01 = [](double v) { return std::clamp(v, 0.0, 1.0); };
  const Errors paper = errors_of(table, [&](double a, double b) { return clamp01(sym2(pp, a, b) / sym2(pq, a, b)); });
  RationalFitOptions o;
  o.basis = RationalBasis::TwoDSymmetric;
  o.num_degree = o.den_degree = 2;
  o.clamp = true;
  const RationalFit f = fit_rational(table, o);
  const Errors ours = errors_of(
      table, [&](double a, double b) { return clamp01(sym2(f.numerator, a, b) / sym2(f.denominator, a, b)); });
  EXPECT_NEAR(ours.max, f.max_abs_error, 1e-12);  // the fit reports the clamped error
  EXPECT_LE(ours.rms, paper.rms);
  EXPECT_LE(ours.max, paper.max);  // 0.0149 against 0.0167
  o.minimax = true;
  o.minimax_iterations = 30;
  const RationalFit m = fit_rational(table, o);
  EXPECT_LE(m.max_abs_error, 0.8 * paper.max);  // 0.0113 against 0.0167
}

TEST(RationalFit, ReadsAndChecksTables) {
  TempDir dir;
  bool two_d = false;
  auto t = read_rational_csv(dir.write("a.csv", "x,value\r\n0,1\n 0.5 , 2 \n\n1,3\n"), &two_d);
  ASSERT_EQ(t.size(), 3u);
  EXPECT_FALSE(two_d);
  EXPECT_EQ(t[1].x, 0.5);
  EXPECT_EQ(t[1].value, 2);
  t = read_rational_csv(dir.write("b.csv", "x,y,value\n0,1,2\n"), &two_d);
  EXPECT_TRUE(two_d);
  EXPECT_EQ(t[0].y, 1);
  const auto message = [&](const std::string& text) {
    try {
      read_rational_csv(dir.write("c.csv", text), &two_d);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message("a,b\n1,2\n").find("line 1: expected the header"), std::string::npos);
  EXPECT_NE(message("x,value\n1,2\n3\n").find("line 3: expected 2 values, got 1"), std::string::npos);
  EXPECT_NE(message("x,value\n1,nan\n").find("line 2: value 2: expected a finite number, got 'nan'"),
            std::string::npos);
  EXPECT_NE(message("x,value\n1,1e999\n").find("line 2: value 2: expected a finite number"), std::string::npos);
  EXPECT_NE(message("x,value\n1,2x\n").find("line 2: value 2"), std::string::npos);
  EXPECT_NE(message("x,value\n1,\n").find("line 2: value 2"), std::string::npos);
  EXPECT_NE(message("x,value\n1e13,1\n").find("beyond"), std::string::npos);
  EXPECT_NE(message("x,value\n").find("no samples"), std::string::npos);
  EXPECT_NE(message("").find("empty"), std::string::npos);
  EXPECT_THROW(read_rational_csv(dir.path() / "missing.csv", &two_d), InputError);
}

// The command: a fit written as JSON, and bad flags, tables and outputs refused with one line and exit status 1.
TEST(RationalFit, Command) {
  using test::kozu;
  using test::run_command;
  TempDir dir;
  std::string csv = "x,value\n";
  for (int i = 0; i <= 20; ++i) csv += fmt::format("{},{}\n", i / 20.0, (1 + i / 20.0) / (1 + 0.5 * i / 20.0));
  const auto data = dir.write("d.csv", csv);
  const auto out = dir.path() / "f.json";
  std::string log;
  ASSERT_EQ(run_command(fmt::format("{} fit-rational '{}' --num 1 --den 1 --constraint 0=1 --json '{}'", kozu(),
                                    data.string(), out.string()),
                        &log),
            0)
      << log;
  const nlohmann::json j = test::read_json(out);
  EXPECT_NEAR(j["numerator"][0].get<double>(), 1, 1e-12);
  EXPECT_NEAR(j["numerator"][1].get<double>(), 1, 1e-9);
  EXPECT_NEAR(j["denominator"][1].get<double>(), 0.5, 1e-9);
  EXPECT_EQ(j["denominator"][0].get<double>(), 1.0);
  EXPECT_LT(j["max_abs_error"].get<double>(), 1e-12);
  EXPECT_TRUE(j.contains("mean_abs_error"));

  const auto two = dir.write("two.csv", "x,y,value\n0,0,1\n1,0,2\n0,1,2\n1,1,3\n");
  const std::string base = fmt::format("{} fit-rational '{}'", kozu(), data.string());
  const std::string json = fmt::format("--json '{}'", (dir.path() / "g.json").string());
  const struct {
    std::string args, message;
    int status;
  } cases[] = {
      {base + " --num -1 --den 1 " + json, "error: kozu fit-rational: --num: expected an integer in [0, 20]", 1},
      {base + " --num 1 --den 1 --json '" + dir.path().string() + "'", "--json", 1},  // a folder
      {base + " --num 1 --den 1 --constraint 0 " + json, "error: kozu fit-rational: --constraint: one '=' is needed",
       1},
      {base + " --num 1 --den 1 --constraint 0,1=2 " + json, "--constraint: a one-variable table", 1},
      {base + " --num 1 --den 1 --2d-symmetric " + json, "--2d-symmetric:", 1},
      {base + " --num 1 --num-terms 1,x --den 1 " + json, "--num and --num-terms exclude each other", 2},
      {base + " --num 1 --den-terms x " + json, "--den-terms: 1 must be among the terms", 1},
      {base + " --num 1 --den 1 --clamp 1,0 " + json, "--clamp: expected LO < HI", 1},
      {base + " --num 1 --den 1 --minimax --no-refine " + json, "--minimax:", 1},
      {base + " --num 1 --den 1 --constraint 0=1 --constraint 0=2 " + json, "constraints are not independent", 1},
      {base + " --num 1 --den 1 --json /proc/x.json", "--json /proc/x.json", 1},
      {fmt::format("{} fit-rational '{}' --num 1 --den 1 {}", kozu(), (dir.path() / "no.csv").string(), json),
       "no.csv: cannot", 1},
      {fmt::format("{} fit-rational '{}' --num 1 --den 0 --constraint 0=1 {}", kozu(), two.string(), json),
       "--constraint: a two-variable table needs both coordinates", 1},
      {fmt::format("{} fit-rational '{}' --num 11 --den 0 {}", kozu(), two.string(), json), "--num:", 1},
      {base + " --num 1 " + json, "error: kozu fit-rational: --den or --den-terms is required", 2},
  };
  for (const auto& c : cases) {
    EXPECT_EQ(run_command(c.args, &log), c.status) << c.args << "\n" << log;
    EXPECT_NE(log.find(c.message), std::string::npos) << c.args << "\n" << log;
    EXPECT_EQ(std::count(log.begin(), log.end(), '\n'), 1) << c.args << "\n" << log;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "g.json"));
  // The symmetric fit of a two-variable table, and the constraint there.
  ASSERT_EQ(run_command(fmt::format("{} fit-rational '{}' --num 1 --den 0 --2d-symmetric --constraint 1,1=3 {}", kozu(),
                                    two.string(), json),
                        &log),
            0)
      << log;
  const nlohmann::json s = test::read_json(dir.path() / "g.json");
  EXPECT_EQ(s["numerator_terms"], nlohmann::json({"1", "x + y"}));
  EXPECT_NEAR(s["numerator"][1].get<double>(), 1.0, 1e-12);
}

}  // namespace
}  // namespace kozu
