// Least-squares fitting of a rational function P/Q to a table, with equality constraints, in one variable or in two
// (general or symmetric), as `kozu fit-rational` offers it.
//
// Citation: D. Chan, "Material Advances in Call of Duty: WWII", SIGGRAPH 2018 course Advances in Real-Time
// Rendering in Games, §3 "Rational function fitting" (after Schlick 1994's "kernel conditions").
//
// Equation map:
//   eq. (39)        f(x) = (c0 + c1 x + … + cN x^N) / (1 + d1 x + … + dM x^M): Q's constant term is 1, which removes
//                   the scale shared by P and Q and makes f(0) = c0
//   eq. (40)/(42)   the paper's unconstrained and constrained fits of the gloss → shortened-normal-length table
//   eq. (41)        a constraint f(X) = Y is linear in the coefficients once multiplied by Q: P(X) − Y Q(X) = 0
//   eqs. (35)–(37)  the symmetric two-variable form: terms x^i y^j + x^j y^i (x^i y^i when i = j), for P and Q
//   eq. (63)        a two-variable fit of chosen terms (1, x, y, x², y², xy, x³, y³ over the same): explicit term
//                   lists (RationalFitOptions::num_terms, den_terms)
//
// Method:
//   1. Linearised least squares (eq. 39 multiplied out): P(x_k) − v_k (Q(x_k) − 1) = v_k is linear in the unknown
//      coefficients; solved by Householder QR in long double with every column scaled to unit norm.
//   2. Constraints (eq. 41) as rows C c = d; the unknowns become c = c0 + N z, c0 the minimum-norm solution and N an
//      orthonormal basis of C's null space (both from a QR of Cᵀ), so every later step meets them exactly.
//   3. Refinement (unless disabled): Levenberg–Marquardt on the true residual P/Q − v over z. The linearised
//      problem weights each sample's error by Q(x_k), so its minimum is not the least-squares fit of f itself (the
//      fit the paper made with Mathematica's FindFit). Two starts: step 1's solution, and the polynomial fit
//      (Q = 1), which has no pole where step 1's may have one; steps are taken only when they lower the sum of
//      squares and keep Q > 0 over the data; the better end is kept.
//   4. Options: a clamped residual clamp(P/Q, lo, hi) − v (eq. 37's clamp, so that a table with a flat part is
//      fitted where it is not flat), and a minimax fit (Lawson's iteratively reweighted least squares on step 3).
//
// Monomial order (numerator and denominator alike, lowest total degree first):
//   one variable     1, x, x², …
//   two variables    by total degree d = 0, 1, …; within a degree x^d, x^(d−1) y, …, y^d
//   symmetric        by total degree d; within it i = d, d − 1, … ≥ d/2: x^i y^(d−i) + x^(d−i) y^i, one term
//                    x^i y^i when i = d − i (so degree 2 is 1, x + y, x² + y², xy: the order of eqs. 35–36)
//
// Deviations: none in the model; the paper does not say how FindFit was started or weighted, and this fit is
// deterministic (no random start).
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace kozu {

enum class RationalBasis { OneD, TwoD, TwoDSymmetric };

// A sample (or a constraint): value at (x, y); y is unused in one variable.
struct RationalSample {
  double x = 0, y = 0, value = 0;
};

struct RationalFitOptions {
  RationalBasis basis = RationalBasis::OneD;
  int num_degree = 1;
  int den_degree = 1;
  // Explicit terms instead of all those up to the degree (e.g. eq. 63's 1, x, y, x², y², xy, x³, y³), as
  // rational_terms lists them, (i, j) = x^i y^j; the denominator's must include (0, 0), whose coefficient is 1.
  std::vector<std::pair<int, int>> num_terms, den_terms;
  std::vector<RationalSample> constraints;  // f(x, y) = value, met exactly (eq. 41)
  bool refine = true;                       // Levenberg–Marquardt on P/Q − v after the linearised solve
  int max_iterations = 200;                 // Levenberg–Marquardt steps of one solve
  // The residual is clamp(P/Q, lo, hi) − v (eq. 37 clamps its fit to [0, 1]): samples where the clamp holds the
  // fit at the value cost nothing, so the rational part is free to pass beyond the range there.
  bool clamp = false;
  double clamp_lo = 0, clamp_hi = 1;
  // Minimise the largest error instead of the sum of squares (Lawson's iteratively reweighted least squares
  // from the least-squares fit; needs refine).
  bool minimax = false;
  int minimax_iterations = 100;
};

struct RationalFit {
  RationalBasis basis = RationalBasis::OneD;
  std::vector<std::pair<int, int>> numerator_terms, denominator_terms;  // the denominator's (0, 0) first
  std::vector<double> numerator;                                        // one per numerator term
  std::vector<double> denominator;                                      // one per denominator term, [0] = 1
  double max_abs_error = 0, mean_abs_error = 0, rms_error = 0;          // of P/Q − v (clamped) over the samples
  double linear_max_abs_error = 0;  // the same for the linearised solve alone (steps 1–2)
  int iterations = 0;               // accepted Levenberg–Marquardt steps, in all

  // P(x, y) / Q(x, y), unclamped.
  double operator()(double x, double y = 0) const;
};

// Limits of a fit (checked by fit_rational and by the command before reading a table).
inline constexpr int kMaxRationalDegree1D = 20;
inline constexpr int kMaxRationalDegree2D = 10;
inline constexpr size_t kMaxRationalUnknowns = 64;
inline constexpr size_t kMaxRationalSamples = 100000;

// The exponents (i, j) of x^i y^j of each term, in the order above (y's exponent 0 in one variable); for the
// symmetric basis, the term is x^i y^j + x^j y^i (once when i = j).
std::vector<std::pair<int, int>> rational_terms(RationalBasis basis, int degree);
// "1", "x^2", "x*y", "x^2*y + x*y^2": the term names, for the JSON output and the docs.
std::string rational_term_name(RationalBasis basis, int i, int j);

// P(x, y) / Q(x, y) of the coefficients of all terms up to a degree (the degree from the count), or of the terms given.
double rational_eval(RationalBasis basis, const std::vector<double>& numerator, const std::vector<double>& denominator,
                     double x, double y = 0);
double rational_eval(RationalBasis basis, const std::vector<std::pair<int, int>>& numerator_terms,
                     const std::vector<double>& numerator, const std::vector<std::pair<int, int>>& denominator_terms,
                     const std::vector<double>& denominator, double x, double y = 0);
// A term list as `--num-terms` takes it: "1,x,y,x^2,x*y,y^3", each 1 or a product of x, y, x^k, y^k (for the
// symmetric basis x^i*y^j stands for the pair). Throws std::invalid_argument naming the term.
std::vector<std::pair<int, int>> parse_rational_terms(std::string_view text, RationalBasis basis);

// Fits P/Q to the samples. Throws std::invalid_argument for a bad request (degrees, too few samples for the unknowns,
// constraints that are dependent or contradictory, a fit whose denominator changes sign across the data: a pole).
RationalFit fit_rational(const std::vector<RationalSample>& samples, const RationalFitOptions& options);

// Reads a table: a header row `x,value` (one variable) or `x,y,value` (two), then one row of finite numbers per
// sample; blank lines and a final newline are allowed, spaces around values too. Throws InputError naming the file
// and the line. `*two_d` says which header it had.
std::vector<RationalSample> read_rational_csv(const std::filesystem::path& file, bool* two_d);

}  // namespace kozu
