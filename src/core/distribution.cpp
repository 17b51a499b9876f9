#include "core/distribution.h"

#include <numeric>
#include <stdexcept>

namespace kozu {

AliasTable::AliasTable(std::span<const float> weights) : bins_(weights.size()) {
  if (weights.empty()) return;
  double sum = 0;
  for (float w : weights) sum += std::max(0.0f, w);
  const size_t n = weights.size();
  if (!(sum > 0)) {
    // All zero: fall back to uniform so that sampling stays defined.
    for (size_t i = 0; i < n; ++i) bins_[i] = {1.0f, 1.0f / n, static_cast<uint32_t>(i)};
    return;
  }
  std::vector<double> scaled(n);
  std::vector<uint32_t> small, large;
  for (size_t i = 0; i < n; ++i) {
    const double p = std::max(0.0f, weights[i]) / sum;
    bins_[i].p = static_cast<float>(p);
    scaled[i] = p * n;
    (scaled[i] < 1.0 ? small : large).push_back(static_cast<uint32_t>(i));
  }
  while (!small.empty() && !large.empty()) {
    const uint32_t s = small.back();
    small.pop_back();
    const uint32_t l = large.back();
    bins_[s].q = static_cast<float>(scaled[s]);
    bins_[s].alias = l;
    scaled[l] = (scaled[l] + scaled[s]) - 1.0;
    if (scaled[l] < 1.0) {
      large.pop_back();
      small.push_back(l);
    }
  }
  // Leftovers are 1 up to rounding.
  for (uint32_t i : small) bins_[i] = {1.0f, bins_[i].p, i};
  for (uint32_t i : large) bins_[i] = {1.0f, bins_[i].p, i};
}

uint32_t AliasTable::sample(float u, float* u_remapped) const {
  const float x = u * static_cast<float>(bins_.size());
  const uint32_t i = std::min(static_cast<uint32_t>(x), static_cast<uint32_t>(bins_.size() - 1));
  const float up = std::min(x - static_cast<float>(i), kOneMinusEpsilon);
  const float q = bins_[i].q;
  if (up < q) {
    if (u_remapped) *u_remapped = std::min(up / q, kOneMinusEpsilon);
    return i;
  }
  if (u_remapped) *u_remapped = std::min((up - q) / (1.0f - q), kOneMinusEpsilon);
  return bins_[i].alias;
}

Distribution1D::Distribution1D(std::span<const float> func) : func_(func.begin(), func.end()), cdf_(func.size() + 1) {
  if (func_.empty()) throw std::invalid_argument("Distribution1D needs at least one cell");
  const size_t n = func_.size();
  // Negative weights are treated as zero, as in AliasTable.
  for (float& f : func_) f = std::isfinite(f) ? std::max(f, 0.0f) : 0.0f;
  double acc = 0;
  cdf_[0] = 0;
  std::vector<double> cdf(n + 1, 0.0);
  for (size_t i = 0; i < n; ++i) {
    acc += func_[i] / static_cast<double>(n);
    cdf[i + 1] = acc;
  }
  integral_ = static_cast<float>(acc);
  if (acc == 0) {
    for (size_t i = 1; i <= n; ++i) cdf_[i] = static_cast<float>(i) / n;
  } else {
    for (size_t i = 1; i <= n; ++i) cdf_[i] = static_cast<float>(cdf[i] / acc);
  }
  cdf_[n] = 1.0f;
  guide_.resize(n + 1);
  for (size_t k = 0; k <= n; ++k) {
    const float u = static_cast<float>(k) / static_cast<float>(n);
    guide_[k] = static_cast<uint32_t>(std::upper_bound(cdf_.begin(), cdf_.end(), u) - cdf_.begin());
  }
}

float Distribution1D::sample(float u, float* pdf, uint32_t* cell) const {
  const size_t n = func_.size();
  // Last cdf entry <= u. u n's rounding may put floor(u n) one off the exact k with k / n <= u < (k + 1) / n, so the
  // search spans the guide entries one either side: the first cdf entry > u lies between them.
  const float un = u * static_cast<float>(n);
  const size_t k = un > 0.0f ? std::min(static_cast<size_t>(un), n) : 0;  // NaN and u < 0 search from the start
  const auto first = cdf_.begin() + (k > 1 ? guide_[k - 1] : 0);
  const auto last = cdf_.begin() + std::min<size_t>(guide_[std::min(k + 2, n)] + 1, n + 1);
  const auto it = std::upper_bound(first, last, u);
  size_t i = static_cast<size_t>(std::max<ptrdiff_t>(0, (it - cdf_.begin()) - 1));
  i = std::min(i, n - 1);
  // Skip zero-width cells that upper_bound can land on when u equals a cdf value exactly.
  while (cdf_[i + 1] - cdf_[i] <= 0.0f && i + 1 < n) ++i;
  if (cell) *cell = static_cast<uint32_t>(i);
  float du = u - cdf_[i];
  const float width = cdf_[i + 1] - cdf_[i];
  if (width > 0) du /= width;
  if (pdf) *pdf = integral_ > 0 ? func_[i] / integral_ : 1.0f;
  // Rounding in (i + du) / n can carry x across the cell edge (possibly into a zero-weight cell);
  // nudge it back so that pdf(x) agrees with the cell that was sampled.
  float x = std::min((static_cast<float>(i) + du) / static_cast<float>(n), kOneMinusEpsilon);
  const auto cell_of = [n](float y) { return std::min(static_cast<size_t>(y * static_cast<float>(n)), n - 1); };
  while (x > 0.0f && cell_of(x) > i) x = std::nextafter(x, 0.0f);
  while (cell_of(x) < i) x = std::nextafter(x, 1.0f);
  return x;
}

float Distribution1D::pdf(float x) const {
  const size_t n = func_.size();
  const size_t i = std::min(static_cast<size_t>(std::max(0.0f, x) * n), n - 1);
  return integral_ > 0 ? func_[i] / integral_ : 1.0f;
}

float Distribution1D::invert(float x) const {
  const size_t n = func_.size();
  const float fx = std::clamp(x, 0.0f, 1.0f) * n;
  const size_t i = std::min(static_cast<size_t>(fx), n - 1);
  const float t = fx - static_cast<float>(i);
  return cdf_[i] + t * (cdf_[i + 1] - cdf_[i]);
}

Distribution2D::Distribution2D(std::span<const float> func, int nu, int nv) : nu_(nu), nv_(nv) {
  conditional_.reserve(nv);
  std::vector<float> marginal(nv);
  for (int v = 0; v < nv; ++v) {
    conditional_.emplace_back(func.subspan(static_cast<size_t>(v) * nu, nu));
    marginal[v] = conditional_.back().integral();
  }
  marginal_ = Distribution1D(marginal);
}

Vec2 Distribution2D::sample(const Vec2& u, float* pdf) const {
  float pdf_v, pdf_u;
  uint32_t row;
  const float v = marginal_.sample(u.y, &pdf_v, &row);
  const float x = conditional_[row].sample(u.x, &pdf_u);
  if (pdf) *pdf = pdf_u * pdf_v;
  return Vec2(x, v);
}

float Distribution2D::pdf(const Vec2& p) const {
  const int row = std::clamp(static_cast<int>(p.y * nv_), 0, nv_ - 1);
  const int col = std::clamp(static_cast<int>(p.x * nu_), 0, nu_ - 1);
  const float integral = marginal_.integral();
  return integral > 0 ? conditional_[row].cell_value(col) / integral : 1.0f;
}

Vec2 Distribution2D::invert(const Vec2& p) const {
  const int row = std::clamp(static_cast<int>(p.y * nv_), 0, nv_ - 1);
  return Vec2(conditional_[row].invert(p.x), marginal_.invert(p.y));
}

}  // namespace kozu
