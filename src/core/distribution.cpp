#include "core/distribution.h"

#include <algorithm>
#include <cmath>
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

namespace distribution_row {

float build(std::span<const float> func, CdfCell* cells, uint32_t* guide) {
  const size_t n = func.size();
  std::vector<double> cdf(n + 1, 0.0);
  double acc = 0;
  for (size_t i = 0; i < n; ++i) {
    // Negative weights are treated as zero, as in AliasTable.
    const float f = std::isfinite(func[i]) ? std::max(func[i], 0.0f) : 0.0f;
    cells[i].func = f;
    acc += f / static_cast<double>(n);
    cdf[i + 1] = acc;
  }
  cells[n].func = 0.0f;
  cells[0].cdf = 0.0f;
  if (acc == 0) {
    for (size_t i = 1; i <= n; ++i) cells[i].cdf = static_cast<float>(i) / n;
  } else {
    for (size_t i = 1; i <= n; ++i) cells[i].cdf = static_cast<float>(cdf[i] / acc);
  }
  cells[n].cdf = 1.0f;
  const auto by_cdf = [](float u, const CdfCell& c) { return u < c.cdf; };
  for (size_t k = 0; k <= n; ++k) {
    const float u = static_cast<float>(k) / static_cast<float>(n);
    guide[k] = static_cast<uint32_t>(std::upper_bound(cells, cells + n + 1, u, by_cdf) - cells);
  }
  return static_cast<float>(acc);
}

float sample(const CdfCell* cells, const uint32_t* guide, size_t n, float integral, float u, float* pdf,
             uint32_t* cell) {
  // Last cdf entry <= u. u n's rounding may put floor(u n) one off the exact k with k / n <= u < (k + 1) / n, so the
  // search spans the guide entries one either side: the first cdf entry > u lies between them.
  const float un = u * static_cast<float>(n);
  const size_t k = un > 0.0f ? std::min(static_cast<size_t>(un), n) : 0;  // NaN and u < 0 search from the start
  const CdfCell* first = cells + (k > 1 ? guide[k - 1] : 0);
  const CdfCell* last = cells + std::min<size_t>(guide[std::min(k + 2, n)] + 1, n + 1);
  const CdfCell* it = std::upper_bound(first, last, u, [](float v, const CdfCell& c) { return v < c.cdf; });
  size_t i = static_cast<size_t>(std::max<ptrdiff_t>(0, (it - cells) - 1));
  i = std::min(i, n - 1);
  // Skip zero-width cells that upper_bound can land on when u equals a cdf value exactly.
  while (cells[i + 1].cdf - cells[i].cdf <= 0.0f && i + 1 < n) ++i;
  if (cell) *cell = static_cast<uint32_t>(i);
  float du = u - cells[i].cdf;
  const float width = cells[i + 1].cdf - cells[i].cdf;
  if (width > 0) du /= width;
  if (pdf) *pdf = integral > 0 ? cells[i].func / integral : 1.0f;
  // Rounding in (i + du) / n can carry x across the cell edge (possibly into a zero-weight cell);
  // nudge it back so that pdf(x) agrees with the cell that was sampled.
  float x = std::min((static_cast<float>(i) + du) / static_cast<float>(n), kOneMinusEpsilon);
  const auto cell_of = [n](float y) { return std::min(static_cast<size_t>(y * static_cast<float>(n)), n - 1); };
  while (x > 0.0f && cell_of(x) > i) x = std::nextafter(x, 0.0f);
  while (cell_of(x) < i) x = std::nextafter(x, 1.0f);
  return x;
}

float invert(const CdfCell* cells, size_t n, float x) {
  const float fx = std::clamp(x, 0.0f, 1.0f) * n;
  const size_t i = std::min(static_cast<size_t>(fx), n - 1);
  const float t = fx - static_cast<float>(i);
  return cells[i].cdf + t * (cells[i + 1].cdf - cells[i].cdf);
}

}  // namespace distribution_row

Distribution1D::Distribution1D(std::span<const float> func) {
  if (func.empty()) throw std::invalid_argument("Distribution1D needs at least one cell");
  cells_.resize(func.size() + 1);
  guide_.resize(func.size() + 1);
  integral_ = distribution_row::build(func, cells_.data(), guide_.data());
}

float Distribution1D::pdf(float x) const {
  const size_t n = size();
  const size_t i = std::min(static_cast<size_t>(std::max(0.0f, x) * n), n - 1);
  return integral_ > 0 ? cells_[i].func / integral_ : 1.0f;
}

Distribution2D::Distribution2D(std::span<const float> func, int nu, int nv) : nu_(nu), nv_(nv) {
  if (nu <= 0 || nv <= 0) throw std::invalid_argument("Distribution2D needs at least one cell");
  cells_.resize(row_offset(nv));
  guide_.resize(row_offset(nv));
  row_integral_.resize(nv);
  for (int v = 0; v < nv; ++v)
    row_integral_[v] = distribution_row::build(func.subspan(static_cast<size_t>(v) * nu, nu), &cells_[row_offset(v)],
                                               &guide_[row_offset(v)]);
  marginal_ = Distribution1D(row_integral_);
}

Vec2 Distribution2D::sample(const Vec2& u, float* pdf) const {
  float pdf_v, pdf_u;
  uint32_t row;
  const float v = marginal_.sample(u.y, &pdf_v, &row);
  const size_t offset = row_offset(static_cast<int>(row));
  const float x = distribution_row::sample(&cells_[offset], &guide_[offset], static_cast<size_t>(nu_),
                                           row_integral_[row], u.x, &pdf_u, nullptr);
  if (pdf) *pdf = pdf_u * pdf_v;
  return Vec2(x, v);
}

float Distribution2D::pdf(const Vec2& p) const {
  const int row = std::clamp(static_cast<int>(p.y * nv_), 0, nv_ - 1);
  const int col = std::clamp(static_cast<int>(p.x * nu_), 0, nu_ - 1);
  const float integral = marginal_.integral();
  return integral > 0 ? cells_[row_offset(row) + col].func / integral : 1.0f;
}

Vec2 Distribution2D::invert(const Vec2& p) const {
  const int row = std::clamp(static_cast<int>(p.y * nv_), 0, nv_ - 1);
  return Vec2(distribution_row::invert(&cells_[row_offset(row)], static_cast<size_t>(nu_), p.x), marginal_.invert(p.y));
}

}  // namespace kozu
