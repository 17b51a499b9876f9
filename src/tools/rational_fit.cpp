// Rational least-squares fits with equality constraints (Chan 2018 §3); see rational_fit.h.
#include "tools/rational_fit.h"

#include "core/error.h"
#include "core/file_io.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string_view>
#include <utility>

namespace kozu {

namespace {

using Real = long double;

// A dense row-major matrix in long double (the solves are small: at most kMaxRationalUnknowns columns).
struct Matrix {
  size_t rows = 0, cols = 0;
  std::vector<Real> a;
  Matrix(size_t r, size_t c) : rows(r), cols(c), a(r * c, 0) {}
  Real& operator()(size_t r, size_t c) { return a[r * cols + c]; }
  Real operator()(size_t r, size_t c) const { return a[r * cols + c]; }
};

// Householder QR of A (rows >= cols) in place: R in the upper triangle, the reflectors kept to apply Qᵀ. The
// columns are scaled to unit norm first (scale[j] multiplies column j), so that rank is judged on equal terms.
struct HouseholderQr {
  Matrix qr;
  std::vector<Real> beta, scale;
  size_t rank = 0;

  explicit HouseholderQr(Matrix m) : qr(std::move(m)), beta(qr.cols, 0), scale(qr.cols, 1) {
    const size_t n = qr.cols, rows = qr.rows;
    for (size_t j = 0; j < n; ++j) {
      Real s = 0;
      for (size_t i = 0; i < rows; ++i) s += qr(i, j) * qr(i, j);
      scale[j] = s > 0 ? 1 / std::sqrt(s) : 1;
      for (size_t i = 0; i < rows; ++i) qr(i, j) *= scale[j];
    }
    for (size_t k = 0; k < n && k < rows; ++k) {
      Real norm = 0;
      for (size_t i = k; i < rows; ++i) norm += qr(i, k) * qr(i, k);
      norm = std::sqrt(norm);
      if (norm == 0) {
        diag_.push_back(0);
        continue;
      }
      const Real alpha = qr(k, k) > 0 ? -norm : norm;  // the sign that avoids cancellation in x1 − α
      qr(k, k) -= alpha;                               // v = x − α e1, stored on and below the diagonal
      Real vtv = 0;
      for (size_t i = k; i < rows; ++i) vtv += qr(i, k) * qr(i, k);
      beta[k] = vtv > 0 ? 2 / vtv : 0;
      for (size_t j = k + 1; j < n; ++j) {
        Real dot = 0;
        for (size_t i = k; i < rows; ++i) dot += qr(i, k) * qr(i, j);
        dot *= beta[k];
        for (size_t i = k; i < rows; ++i) qr(i, j) -= dot * qr(i, k);
      }
      diag_.push_back(alpha);
    }
    diag_.resize(n, 0);
    Real largest = 0;
    for (const Real d : diag_) largest = std::max(largest, std::fabs(d));
    for (const Real d : diag_) rank += std::fabs(d) > largest * 1e-15L * Real(std::max<size_t>(rows, 1));
  }

  Real r(size_t i, size_t j) const { return i == j ? diag_[i] : qr(i, j); }

  // y ← Qᵀ y.
  void apply_qt(std::vector<Real>& y) const {
    for (size_t k = 0; k < qr.cols && k < qr.rows; ++k) {
      if (beta[k] == 0) continue;
      Real dot = 0;
      for (size_t i = k; i < qr.rows; ++i) dot += qr(i, k) * y[i];
      dot *= beta[k];
      for (size_t i = k; i < qr.rows; ++i) y[i] -= dot * qr(i, k);
    }
  }
  // y ← Q y.
  void apply_q(std::vector<Real>& y) const {
    for (size_t k = std::min(qr.cols, qr.rows); k-- > 0;) {
      if (beta[k] == 0) continue;
      Real dot = 0;
      for (size_t i = k; i < qr.rows; ++i) dot += qr(i, k) * y[i];
      dot *= beta[k];
      for (size_t i = k; i < qr.rows; ++i) y[i] -= dot * qr(i, k);
    }
  }
  // The least-squares solution of A x = b (full column rank checked by the caller).
  std::vector<Real> solve(std::vector<Real> b) const {
    apply_qt(b);
    const size_t n = qr.cols;
    std::vector<Real> x(n, 0);
    for (size_t i = n; i-- > 0;) {
      Real s = b[i];
      for (size_t j = i + 1; j < n; ++j) s -= r(i, j) * x[j];
      x[i] = s / r(i, i);
    }
    for (size_t j = 0; j < n; ++j) x[j] *= scale[j];
    return x;
  }

 private:
  std::vector<Real> diag_;
};

Real power(Real x, int k) {
  Real p = 1;
  for (int i = 0; i < k; ++i) p *= x;
  return p;
}

// The value of each term at (x, y).
void eval_terms(RationalBasis basis, const std::vector<std::pair<int, int>>& terms, Real x, Real y, Real* out) {
  for (size_t t = 0; t < terms.size(); ++t) {
    const auto [i, j] = terms[t];
    if (basis == RationalBasis::OneD)
      out[t] = power(x, i);
    else if (basis == RationalBasis::TwoD || i == j)
      out[t] = power(x, i) * power(y, j);
    else
      out[t] = power(x, i) * power(y, j) + power(x, j) * power(y, i);  // Chan 2018 eqs. (35)–(36)
  }
}

}  // namespace

std::vector<std::pair<int, int>> rational_terms(RationalBasis basis, int degree) {
  std::vector<std::pair<int, int>> t;
  for (int d = 0; d <= degree; ++d) {
    if (basis == RationalBasis::OneD) {
      t.emplace_back(d, 0);
      continue;
    }
    for (int i = d; i >= 0; --i) {
      if (basis == RationalBasis::TwoDSymmetric && i < d - i) break;
      t.emplace_back(i, d - i);
    }
  }
  return t;
}

std::string rational_term_name(RationalBasis basis, int i, int j) {
  const auto mono = [](int a, int b) {
    const std::string px = a == 0 ? "" : a == 1 ? "x" : fmt::format("x^{}", a);
    const std::string py = b == 0 ? "" : b == 1 ? "y" : fmt::format("y^{}", b);
    if (px.empty() && py.empty()) return std::string("1");
    return fmt::format("{}{}{}", px, !px.empty() && !py.empty() ? "*" : "", py);
  };
  if (basis == RationalBasis::TwoDSymmetric && i != j) return mono(i, j) + " + " + mono(j, i);
  return mono(i, j);
}

double rational_eval(RationalBasis basis, const std::vector<double>& numerator, const std::vector<double>& denominator,
                     double x, double y) {
  const auto degree_of = [&](size_t count) {
    int d = 0;
    while (rational_terms(basis, d).size() < count) ++d;
    return d;
  };
  return rational_eval(basis, rational_terms(basis, degree_of(numerator.size())), numerator,
                       rational_terms(basis, degree_of(denominator.size())), denominator, x, y);
}

double rational_eval(RationalBasis basis, const std::vector<std::pair<int, int>>& numerator_terms,
                     const std::vector<double>& numerator, const std::vector<std::pair<int, int>>& denominator_terms,
                     const std::vector<double>& denominator, double x, double y) {
  const auto poly = [&](const std::vector<std::pair<int, int>>& terms, const std::vector<double>& c) {
    std::vector<Real> v(terms.size());
    eval_terms(basis, terms, x, y, v.data());
    Real s = 0;
    for (size_t t = 0; t < c.size() && t < terms.size(); ++t) s += Real(c[t]) * v[t];
    return s;
  };
  return double(poly(numerator_terms, numerator) / poly(denominator_terms, denominator));
}

double RationalFit::operator()(double x, double y) const {
  return rational_eval(basis, numerator_terms, numerator, denominator_terms, denominator, x, y);
}

std::vector<std::pair<int, int>> parse_rational_terms(std::string_view text, RationalBasis basis) {
  std::vector<std::pair<int, int>> terms;
  const auto bad = [&](std::string_view term, const std::string& why) {
    return std::invalid_argument(fmt::format("term '{}': {}", term.substr(0, 40), why));
  };
  for (size_t a = 0; a <= text.size();) {
    size_t b = text.find(',', a);
    if (b == std::string_view::npos) b = text.size();
    std::string_view term = text.substr(a, b - a);
    while (!term.empty() && term.front() == ' ') term.remove_prefix(1);
    while (!term.empty() && term.back() == ' ') term.remove_suffix(1);
    a = b + 1;
    int e[2] = {0, 0};
    if (term != "1") {
      for (size_t f = 0; f <= term.size();) {
        size_t g = term.find('*', f);
        if (g == std::string_view::npos) g = term.size();
        const std::string_view factor = term.substr(f, g - f);
        f = g + 1;
        if (factor.empty() || (factor[0] != 'x' && factor[0] != 'y'))
          throw bad(term, "expected 1 or a product of x, y, x^k, y^k");
        int k = 1;
        if (factor.size() > 1) {
          if (factor[1] != '^' || factor.size() < 3) throw bad(term, "expected x^k or y^k");
          const auto [p, ec] = std::from_chars(factor.data() + 2, factor.data() + factor.size(), k);
          if (ec != std::errc() || p != factor.data() + factor.size() || k < 1 || k > kMaxRationalDegree1D)
            throw bad(term, fmt::format("expected a power in [1, {}]", kMaxRationalDegree1D));
        }
        e[factor[0] == 'y' ? 1 : 0] += k;
      }
    }
    if (basis == RationalBasis::OneD && e[1] > 0) throw bad(term, "y in a one-variable fit");
    if (basis == RationalBasis::TwoDSymmetric && e[0] < e[1]) std::swap(e[0], e[1]);  // the pair's first member
    const std::pair<int, int> t{e[0], e[1]};
    if (std::find(terms.begin(), terms.end(), t) != terms.end()) throw bad(term, "given twice");
    terms.push_back(t);
  }
  return terms;
}

namespace {

using Terms = std::vector<std::pair<int, int>>;

// One fit's state: the terms, the constraints' space c = c0 + N z, the sample weights, and the steps of
// fit_rational (rational_fit.h) as methods.
class RationalFitter {
 public:
  RationalFitter(const std::vector<RationalSample>& samples, const RationalFitOptions& o);
  RationalFit run();

 private:
  void check_sizes() const;
  void linear_row(const RationalSample& s, Real* row);
  void constraint_space();
  std::vector<Real> linear_solve();
  std::vector<Real> coefficients(const std::vector<Real>& z) const;
  std::pair<Real, Real> eval_pq(const std::vector<Real>& c, double x, double y);
  Real clamp_value(Real f) const {
    return o_.clamp ? std::clamp(f, Real(o_.clamp_lo), Real(o_.clamp_hi)) : f;  // Chan 2018 eq. (37)
  }
  Real residuals(const std::vector<Real>& c, std::vector<Real>& r);
  bool q_positive(const std::vector<Real>& c);
  int levenberg_marquardt(std::vector<Real>& zz, std::vector<Real>& rr, Real& ss);
  std::optional<std::vector<Real>> polynomial_start() const;
  void refine(std::vector<Real>& z, Real sse, RationalFit& fit);
  void minimax(std::vector<Real>& z, RationalFit& fit);
  void finish(const std::vector<Real>& z, RationalFit& fit);

  const std::vector<RationalSample>& samples_;
  const RationalFitOptions& o_;
  bool one_d_;
  int max_degree_;
  Terms pt_, qt_;
  size_t np_ = 0, nq_ = 0, n_ = 0, m_ = 0, free_ = 0, rows_ = 0;
  std::vector<Real> tp_, tq_, vp_, vq_, w_, c0_;
  Matrix null_basis_{0, 0};
  double lo_ = 0, hi_ = 0;
};

RationalFitter::RationalFitter(const std::vector<RationalSample>& samples, const RationalFitOptions& o)
    : samples_(samples), o_(o), one_d_(o.basis == RationalBasis::OneD) {
  max_degree_ = one_d_ ? kMaxRationalDegree1D : kMaxRationalDegree2D;
  if (o.num_degree < 0 || o.num_degree > max_degree_)
    throw std::invalid_argument(fmt::format("--num: expected a degree in [0, {}], got {}", max_degree_, o.num_degree));
  if (o.den_degree < 0 || o.den_degree > max_degree_)
    throw std::invalid_argument(fmt::format("--den: expected a degree in [0, {}], got {}", max_degree_, o.den_degree));
  pt_ = o.num_terms.empty() ? rational_terms(o.basis, o.num_degree) : o.num_terms;
  qt_ = o.den_terms.empty() ? rational_terms(o.basis, o.den_degree) : o.den_terms;
  // Q's constant term is 1 (Chan 2018 eq. (39)): it must be among the terms, and comes first.
  const auto one = std::find(qt_.begin(), qt_.end(), std::pair{0, 0});
  if (one == qt_.end()) throw std::invalid_argument("the denominator's terms must include 1 (its constant term, 1)");
  std::rotate(qt_.begin(), one, one + 1);
  if (pt_.empty()) throw std::invalid_argument("the numerator has no terms");
  for (const Terms* terms : {&pt_, &qt_})
    for (const auto& [i, j] : *terms)
      if (i < 0 || j < 0 || i + j > max_degree_ || (one_d_ && j != 0))
        throw std::invalid_argument(
            fmt::format("term {}: expected a total degree in [0, {}]", rational_term_name(o.basis, i, j), max_degree_));
  np_ = pt_.size(), nq_ = qt_.size() - 1, n_ = np_ + nq_;  // unknowns: P's terms, Q's but its constant
  m_ = o.constraints.size();
  check_sizes();
  free_ = n_ - m_;
  rows_ = samples.size();
  tp_.resize(np_), tq_.resize(nq_ + 1), vp_.resize(np_), vq_.resize(nq_ + 1);
  w_.assign(rows_, 1);
  if (!samples.empty()) lo_ = samples[0].x, hi_ = lo_;
  for (const RationalSample& s : samples) lo_ = std::min(lo_, s.x), hi_ = std::max(hi_, s.x);
}

void RationalFitter::check_sizes() const {
  if (n_ > kMaxRationalUnknowns)
    throw std::invalid_argument(
        fmt::format("{} coefficients to fit, more than the {} allowed", n_, kMaxRationalUnknowns));
  if (m_ > n_) throw std::invalid_argument(fmt::format("{} constraints for {} coefficients", m_, n_));
  if (samples_.size() < n_ - m_)
    throw std::invalid_argument(fmt::format("{} samples for {} free coefficients: at least as many samples are needed",
                                            samples_.size(), n_ - m_));
  if (samples_.size() > kMaxRationalSamples)
    throw std::invalid_argument(
        fmt::format("{} samples, more than the {} allowed", samples_.size(), kMaxRationalSamples));
}

// A row of the linearised system at (x, y) with value v: [terms of P, −v · terms of Q but 1] · c = v.
void RationalFitter::linear_row(const RationalSample& s, Real* row) {
  eval_terms(o_.basis, pt_, s.x, s.y, tp_.data());
  eval_terms(o_.basis, qt_, s.x, s.y, tq_.data());
  for (size_t j = 0; j < np_; ++j) row[j] = tp_[j];
  for (size_t j = 0; j < nq_; ++j) row[np_ + j] = -Real(s.value) * tq_[j + 1];  // Chan 2018 eq. (39), multiplied out
}

// Step 2: c = c0 + N z meets C c = d exactly (Chan 2018 eq. (41): P(X) − Y Q(X) = 0 is linear in c).
void RationalFitter::constraint_space() {
  c0_.assign(n_, 0);
  null_basis_ = Matrix(n_, free_);
  if (m_ == 0) {
    for (size_t j = 0; j < n_; ++j) null_basis_(j, j) = 1;
    return;
  }
  Matrix ct(n_, m_);  // Cᵀ, each constraint scaled to a unit row so that rank is judged on equal terms
  std::vector<Real> d(m_), row(n_);
  for (size_t k = 0; k < m_; ++k) {
    linear_row(o_.constraints[k], row.data());
    Real norm = 0;
    for (const Real v : row) norm += v * v;
    norm = std::sqrt(norm);
    if (!(norm > 0)) throw std::invalid_argument(fmt::format("constraint {} ties no coefficient", k + 1));
    for (size_t j = 0; j < n_; ++j) ct(j, k) = row[j] / norm;
    d[k] = Real(o_.constraints[k].value) / norm;
  }
  // QR of Cᵀ without column scaling (rows are already unit): Cᵀ = Q [R; 0], so C = [Rᵀ 0] Qᵀ.
  HouseholderQr q(ct);
  if (q.rank < m_)
    throw std::invalid_argument(
        "the constraints are not independent (two fix the same thing, or the form cannot "
        "meet them all)");
  // Rᵀ y = d (R of the scaled columns: undo the scale, C = [Rᵀ 0] Qᵀ with R's column j divided by scale[j]).
  std::vector<Real> y(n_, 0);
  for (size_t i = 0; i < m_; ++i) {
    Real s = d[i];
    for (size_t j = 0; j < i; ++j) s -= q.r(j, i) / q.scale[i] * y[j];
    y[i] = s / (q.r(i, i) / q.scale[i]);
  }
  c0_ = y;
  q.apply_q(c0_);
  for (size_t k = 0; k < free_; ++k) {
    std::vector<Real> e(n_, 0);
    e[m_ + k] = 1;
    q.apply_q(e);
    for (size_t j = 0; j < n_; ++j) null_basis_(j, k) = e[j];
  }
}

std::vector<Real> RationalFitter::coefficients(const std::vector<Real>& z) const {
  std::vector<Real> c = c0_;
  for (size_t j = 0; j < n_; ++j)
    for (size_t k = 0; k < free_; ++k) c[j] += null_basis_(j, k) * z[k];
  return c;
}

// Step 1: the linearised least squares over z: (A N) z = b − A c0.
std::vector<Real> RationalFitter::linear_solve() {
  std::vector<Real> z(free_, 0);
  if (free_ == 0) return z;
  Matrix an(rows_, free_);
  std::vector<Real> rhs(rows_), row(n_);
  for (size_t i = 0; i < rows_; ++i) {
    linear_row(samples_[i], row.data());
    Real ac0 = 0;
    for (size_t j = 0; j < n_; ++j) ac0 += row[j] * c0_[j];
    rhs[i] = Real(samples_[i].value) - ac0;
    for (size_t k = 0; k < free_; ++k) {
      Real s = 0;
      for (size_t j = 0; j < n_; ++j) s += row[j] * null_basis_(j, k);
      an(i, k) = s;
    }
  }
  HouseholderQr q(std::move(an));
  if (q.rank < free_)
    throw std::invalid_argument(fmt::format(
        "the samples do not determine the {} free coefficients (too few distinct points, or a form with more "
        "freedom than the data shows: try lower degrees)",
        free_));
  return q.solve(rhs);
}

// P and Q of coefficients c at (x, y); the terms' values stay in vp_ and vq_ for the Jacobian.
std::pair<Real, Real> RationalFitter::eval_pq(const std::vector<Real>& c, double x, double y) {
  eval_terms(o_.basis, pt_, x, y, vp_.data());
  eval_terms(o_.basis, qt_, x, y, vq_.data());
  Real p = 0, q = vq_[0];
  for (size_t j = 0; j < np_; ++j) p += c[j] * vp_[j];
  for (size_t j = 0; j < nq_; ++j) q += c[np_ + j] * vq_[j + 1];
  return std::pair{p, q};
}

// The residuals clamp(P/Q) − v of coefficients c (the clamp only with options.clamp, as eq. (37) clamps), and their
// sum of squares weighted by w_ (the minimax iteration's weights; all 1 for least squares).
Real RationalFitter::residuals(const std::vector<Real>& c, std::vector<Real>& r) {
  Real sse = 0;
  for (size_t i = 0; i < rows_; ++i) {
    const auto [p, q] = eval_pq(c, samples_[i].x, samples_[i].y);
    r[i] = clamp_value(p / q) - Real(samples_[i].value);
    sse += w_[i] * r[i] * r[i];
  }
  return std::isfinite(sse) ? sse : std::numeric_limits<Real>::infinity();
}

// Whether Q > 0 at every sample and, in one variable, on a fine grid of the data's range (a sign change is a pole
// between samples, which no error at the samples would show; Q(0) = 1 fixes the sign).
bool RationalFitter::q_positive(const std::vector<Real>& c) {
  const auto q_at = [&](double x, double y) { return eval_pq(c, x, y).second; };
  for (const RationalSample& s : samples_)
    if (!(q_at(s.x, s.y) > 0)) return false;
  if (one_d_)
    for (int k = 0; k <= 4096; ++k)
      if (!(q_at(lo_ + (hi_ - lo_) * k / 4096.0, 0) > 0)) return false;
  return true;
}

// Step 3: Levenberg–Marquardt on the true residual, over z (the constraints stay met), from a start whose Q is
// positive over the data; only steps that lower the sum of squares and keep Q positive are taken. Columns of J are
// scaled to unit norm; the damped step solves [J; √λ I] δ = [−r; 0] by QR.
int RationalFitter::levenberg_marquardt(std::vector<Real>& zz, std::vector<Real>& rr, Real& ss) {
  int steps = 0;
  Real lambda = 1e-3L;
  for (int it = 0; it < o_.max_iterations && lambda < 1e12L && ss > 0; ++it) {
    const std::vector<Real> c = coefficients(zz);
    Matrix j(rows_ + free_, free_);
    for (size_t i = 0; i < rows_; ++i) {
      const auto [p, q] = eval_pq(c, samples_[i].x, samples_[i].y);
      const Real f = p / q;
      // ∂f/∂p_k = φ_k / Q, ∂f/∂q_k = −f ψ_k / Q; chained with ∂c/∂z = N; 0 where the clamp holds f, and the
      // row scaled by √w_i.
      const bool held = o_.clamp && (f < Real(o_.clamp_lo) || f > Real(o_.clamp_hi));
      const Real sw = std::sqrt(w_[i]);
      for (size_t k = 0; k < free_; ++k) {
        Real s = 0;
        for (size_t l = 0; l < np_; ++l) s += vp_[l] / q * null_basis_(l, k);
        for (size_t l = 0; l < nq_; ++l) s -= f * vq_[l + 1] / q * null_basis_(np_ + l, k);
        j(i, k) = held ? 0 : s * sw;
      }
    }
    std::vector<Real> col_scale(free_, 1);
    for (size_t k = 0; k < free_; ++k) {
      Real s = 0;
      for (size_t i = 0; i < rows_; ++i) s += j(i, k) * j(i, k);
      col_scale[k] = s > 0 ? 1 / std::sqrt(s) : 1;
      for (size_t i = 0; i < rows_; ++i) j(i, k) *= col_scale[k];
    }
    bool accepted = false;
    while (!accepted && lambda < 1e12L) {
      Matrix aug = j;
      for (size_t k = 0; k < free_; ++k) aug(rows_ + k, k) = std::sqrt(lambda);
      std::vector<Real> rhs(rows_ + free_, 0);
      for (size_t i = 0; i < rows_; ++i) rhs[i] = -std::sqrt(w_[i]) * rr[i];
      HouseholderQr q(std::move(aug));
      const std::vector<Real> step = q.solve(rhs);
      std::vector<Real> trial = zz;
      for (size_t k = 0; k < free_; ++k) trial[k] += step[k] * col_scale[k];
      std::vector<Real> tr(rows_);
      const std::vector<Real> tc = coefficients(trial);
      const Real tsse = residuals(tc, tr);
      if (tsse < ss && q_positive(tc)) {
        const bool converged = ss - tsse <= ss * 1e-15L;
        zz = trial;
        rr = tr;
        ss = tsse;
        lambda = std::max(lambda * 0.3L, 1e-15L);
        accepted = true;
        ++steps;
        if (converged) lambda = 1e12L;  // stop: no further progress worth a step
      } else {
        lambda *= 10;
      }
    }
  }
  return steps;
}

// The polynomial fit (Q = 1, always free of poles) as a point z of the constraints' space; none when the
// constraints need the denominator.
std::optional<std::vector<Real>> RationalFitter::polynomial_start() const {
  RationalFitOptions po = o_;
  po.den_degree = 0;
  po.den_terms = {{0, 0}};
  po.num_terms = pt_;
  po.refine = false;
  try {
    const RationalFit poly = fit_rational(samples_, po);
    std::vector<Real> c(n_, 0);
    for (size_t k = 0; k < np_; ++k) c[k] = poly.numerator[k];
    std::vector<Real> zp(free_, 0);  // c − c0 lies in N's span: z = Nᵀ (c − c0)
    for (size_t k = 0; k < free_; ++k)
      for (size_t l = 0; l < n_; ++l) zp[k] += null_basis_(l, k) * (c[l] - c0_[l]);
    return zp;
  } catch (const std::invalid_argument&) {
    return std::nullopt;
  }
}

// Two starts: the linearised solve, and the polynomial fit for when the linearised solve puts a zero of Q inside the
// data (its weighting by Q makes that cheap for it, as in the detail-gloss table, whose clamped zeros pull Q through
// 0). The better end is kept.
void RationalFitter::refine(std::vector<Real>& z, Real sse, RationalFit& fit) {
  std::vector<std::vector<Real>> starts;
  if (std::isfinite(sse) && q_positive(coefficients(z))) starts.push_back(z);
  if (nq_ > 0)
    if (std::optional<std::vector<Real>> zp = polynomial_start()) starts.push_back(std::move(*zp));
  Real best = std::numeric_limits<Real>::infinity();
  std::vector<Real> best_z = z;
  for (std::vector<Real> zz : starts) {
    std::vector<Real> rr(rows_);
    Real ss = residuals(coefficients(zz), rr);
    const int steps = levenberg_marquardt(zz, rr, ss);
    if (ss < best) best = ss, best_z = zz, fit.iterations = steps;
  }
  z = best_z;
  if (o_.minimax && !starts.empty()) minimax(z, fit);
}

// Lawson's iteration: weighted least squares whose weights grow where the error is largest,
// w_i ← w_i |r_i| / Σ_j w_j |r_j|, each solve started from the last; the smallest maximum error is kept.
void RationalFitter::minimax(std::vector<Real>& z, RationalFit& fit) {
  const auto max_abs = [&](const std::vector<Real>& e) {
    Real largest = 0;
    for (const Real v : e) largest = std::max(largest, std::fabs(v));
    return largest;
  };
  std::vector<Real> rr(rows_);
  residuals(coefficients(z), rr);
  Real best_max = max_abs(rr);
  std::vector<Real> zz = z;
  for (int k = 0; k < o_.minimax_iterations; ++k) {
    Real total = 0;
    for (size_t i = 0; i < rows_; ++i) total += w_[i] * std::fabs(rr[i]);
    if (!(total > 0)) break;
    for (size_t i = 0; i < rows_; ++i) w_[i] = w_[i] * std::fabs(rr[i]) / total * Real(rows_);
    Real ss = residuals(coefficients(zz), rr);
    fit.iterations += levenberg_marquardt(zz, rr, ss);
    const Real e = max_abs(rr);
    if (e < best_max) best_max = e, z = zz;
  }
}

// The coefficients as written (doubles) and their errors; a denominator that is not positive is refused.
void RationalFitter::finish(const std::vector<Real>& z, RationalFit& fit) {
  const std::vector<Real> c = coefficients(z);
  fit.numerator_terms = pt_;
  fit.denominator_terms = qt_;
  fit.numerator.assign(c.begin(), c.begin() + static_cast<std::ptrdiff_t>(np_));
  fit.denominator.push_back(1.0);
  fit.denominator.insert(fit.denominator.end(), c.begin() + static_cast<std::ptrdiff_t>(np_), c.end());
  Real sum = 0, sum2 = 0;
  for (const RationalSample& s : samples_) {
    const double e = std::fabs(double(clamp_value(fit(s.x, s.y))) - s.value);
    fit.max_abs_error = std::max(fit.max_abs_error, e);
    sum += e;
    sum2 += Real(e) * e;
  }
  std::vector<Real> written(n_);
  for (size_t k = 0; k < np_; ++k) written[k] = fit.numerator[k];
  for (size_t k = 0; k < nq_; ++k) written[np_ + k] = fit.denominator[k + 1];
  if (!q_positive(written) || !std::isfinite(fit.max_abs_error))
    throw std::invalid_argument(
        "the fitted denominator is not positive across the data (a pole inside it): try other degrees or constraints");
  fit.mean_abs_error = double(sum / Real(samples_.size()));
  fit.rms_error = double(std::sqrt(sum2 / Real(samples_.size())));
}

RationalFit RationalFitter::run() {
  constraint_space();
  std::vector<Real> z = linear_solve();
  RationalFit fit;
  fit.basis = o_.basis;
  std::vector<Real> r(rows_);
  const Real sse = residuals(coefficients(z), r);
  for (const Real e : r) fit.linear_max_abs_error = std::max(fit.linear_max_abs_error, double(std::fabs(e)));
  if (o_.refine && free_ > 0) refine(z, sse, fit);
  finish(z, fit);
  return fit;
}

}  // namespace

RationalFit fit_rational(const std::vector<RationalSample>& samples, const RationalFitOptions& o) {
  return RationalFitter(samples, o).run();
}

std::vector<RationalSample> read_rational_csv(const std::filesystem::path& file, bool* two_d) {
  const std::string name = file.string();
  // 64 MiB holds kMaxRationalSamples rows of three full-precision numbers many times over.
  const std::string text = read_input_file(file, uint64_t{64} << 20);
  std::vector<RationalSample> samples;
  size_t pos = 0, line = 0;
  int columns = 0;
  const auto trim = [](std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
    return s;
  };
  while (pos < text.size()) {
    const size_t end = std::min(text.find('\n', pos), text.size());
    const std::string_view l = trim(std::string_view(text).substr(pos, end - pos));
    pos = end + 1;
    ++line;
    const std::string where = fmt::format("line {}", line);
    if (l.empty()) continue;
    std::vector<std::string_view> fields;
    for (size_t a = 0;;) {
      const size_t b = l.find(',', a);
      fields.push_back(trim(l.substr(a, b == std::string_view::npos ? std::string_view::npos : b - a)));
      if (b == std::string_view::npos) break;
      a = b + 1;
    }
    if (columns == 0) {
      if (fields.size() == 2 && fields[0] == "x" && fields[1] == "value")
        columns = 2;
      else if (fields.size() == 3 && fields[0] == "x" && fields[1] == "y" && fields[2] == "value")
        columns = 3;
      else
        throw InputError(name, where,
                         fmt::format("expected the header 'x,value' or 'x,y,value', got '{}'",
                                     std::string(l.substr(0, std::min<size_t>(l.size(), 40)))));
      continue;
    }
    if (int(fields.size()) != columns)
      throw InputError(name, where, fmt::format("expected {} values, got {}", columns, fields.size()));
    double v[3] = {0, 0, 0};
    for (int k = 0; k < columns; ++k) {
      const std::string_view f = fields[size_t(k)];
      const auto [p, ec] = std::from_chars(f.data(), f.data() + f.size(), v[k]);
      if (f.empty() || ec != std::errc() || p != f.data() + f.size() || !std::isfinite(v[k]))
        throw InputError(name, where,
                         fmt::format("value {}: expected a finite number, got '{}'", k + 1,
                                     std::string(f.substr(0, std::min<size_t>(f.size(), 40)))));
      // Powers up to the 20th of a sample stay far from long double's range with this bound.
      if (std::fabs(v[k]) > 1e12)
        throw InputError(name, where, fmt::format("value {}: {} is beyond ±1e12", k + 1, v[k]));
    }
    if (samples.size() >= kMaxRationalSamples)
      throw InputError(name, where, fmt::format("more than {} samples", kMaxRationalSamples));
    samples.push_back(columns == 2 ? RationalSample{v[0], 0, v[1]} : RationalSample{v[0], v[1], v[2]});
  }
  if (columns == 0) throw InputError(name, "", "empty: expected the header 'x,value' or 'x,y,value' and samples");
  if (samples.empty()) throw InputError(name, "", "no samples after the header");
  *two_d = columns == 3;
  return samples;
}

}  // namespace kozu
