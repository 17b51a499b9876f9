#include "lights/ltc_texture.h"

#include "core/ltc.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace kozu {

namespace {

// One output sample's 1D weights over the texels first, first + 1, …: the clamped, renormalized Gaussian of
// ltc_texture.h, relative to the nearest texel so that no weight underflows to a 0/0.
struct Taps {
  int first = 0;
  std::vector<float> w;
};

Taps gaussian_taps(float x, float sigma, int n) {
  const float texel = 1.0f / float(n);
  const float nearest = std::clamp(x, 0.5f * texel, 1.0f - 0.5f * texel);
  const double d_min2 = double(x - nearest) * double(x - nearest);
  const double inv_2s2 = 1.0 / (2.0 * double(sigma) * double(sigma));
  constexpr double kCut = 12.5;  // weights below e^-12.5 (3.7e-6) of the nearest texel's are dropped
  const double reach = std::sqrt(kCut / inv_2s2 + d_min2);
  const int lo = std::clamp(int(std::floor((x - reach) * n - 0.5)), 0, n - 1);
  const int hi = std::clamp(int(std::ceil((x + reach) * n - 0.5)), 0, n - 1);
  Taps t;
  t.first = lo;
  double sum = 0.0;
  std::vector<double> w(size_t(hi - lo + 1));
  for (int i = lo; i <= hi; ++i) {
    const double d = double(x) - (i + 0.5) * double(texel);
    const double e = (d * d - d_min2) * inv_2s2;
    w[size_t(i - lo)] = e > kCut ? 0.0 : std::exp(-e);
    sum += w[size_t(i - lo)];
  }
  t.w.resize(w.size());
  for (size_t i = 0; i < w.size(); ++i) t.w[i] = float(w[i] / sum);  // sum >= 1: the nearest texel weighs 1
  return t;
}

}  // namespace

LtcTexture::LtcTexture(std::span<const Rgb> texels, int n) {
  if (n < 1 || texels.size() != size_t(n) * size_t(n)) throw std::invalid_argument("LtcTexture: n × n texels");
  Level base;
  base.origin = 0.5f / float(n);
  base.spacing = 1.0f / float(n);
  base.size = n;
  base.v.assign(texels.begin(), texels.end());
  levels_.push_back(std::move(base));
  // Up to σ = 4: wider filters average the whole square the same way.
  for (int k = 1; std::ldexp(1.0f, k) / float(n) <= 4.0f; ++k) {
    Level l;
    l.sigma = std::ldexp(1.0f, k) / float(n);
    l.spacing = 0.5f * l.sigma;
    l.origin = -kMargin;
    l.size = int(std::ceil((1.0f + 2.0f * kMargin) / l.spacing)) + 1;
    std::vector<Taps> taps(size_t(l.size));
    for (int i = 0; i < l.size; ++i) taps[size_t(i)] = gaussian_taps(l.origin + float(i) * l.spacing, l.sigma, n);
    // Rows first (along a, every texel row), then columns (along b).
    std::vector<Rgb> rows(size_t(n) * size_t(l.size), Rgb(0.0f));
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < l.size; ++i) {
        const Taps& t = taps[size_t(i)];
        Rgb s(0.0f);
        for (size_t q = 0; q < t.w.size(); ++q) s += t.w[q] * texels[size_t(j) * size_t(n) + size_t(t.first) + q];
        rows[size_t(j) * size_t(l.size) + size_t(i)] = s;
      }
    l.v.assign(size_t(l.size) * size_t(l.size), Rgb(0.0f));
    for (int j = 0; j < l.size; ++j) {
      const Taps& t = taps[size_t(j)];
      for (size_t q = 0; q < t.w.size(); ++q) {
        const Rgb* row = &rows[(size_t(t.first) + q) * size_t(l.size)];
        Rgb* out = &l.v[size_t(j) * size_t(l.size)];
        for (int i = 0; i < l.size; ++i) out[i] += t.w[q] * row[i];
      }
    }
    levels_.push_back(std::move(l));
  }
}

Rgb LtcTexture::Level::bilinear(const Vec2& ab) const {
  // Sample coordinates, clamped to the level's extent (the texture's edge for level 0, the margin's for the rest).
  const float last = float(size - 1);
  const float x = std::clamp((ab.x - origin) / spacing, 0.0f, last);
  const float y = std::clamp((ab.y - origin) / spacing, 0.0f, last);
  const int x0 = std::min(int(x), size - 1), y0 = std::min(int(y), size - 1);
  const int x1 = std::min(x0 + 1, size - 1), y1 = std::min(y0 + 1, size - 1);
  const float fx = x - float(x0), fy = y - float(y0);
  const auto at = [&](int i, int j) { return v[size_t(j) * size_t(size) + size_t(i)]; };
  return (1.0f - fy) * ((1.0f - fx) * at(x0, y0) + fx * at(x1, y0)) + fy * ((1.0f - fx) * at(x0, y1) + fx * at(x1, y1));
}

Rgb LtcTexture::lookup(const Vec2& ab_in, float sigma) const {
  const Vec2 ab(std::isfinite(ab_in.x) ? ab_in.x : 0.5f, std::isfinite(ab_in.y) ? ab_in.y : 0.5f);
  if (!(sigma > 0.0f) || levels_.size() == 1) return levels_[0].bilinear(ab);
  // Linear in σ between the texture (σ = 0) and level 1, linear in log σ above.
  size_t k = 1;
  while (k + 1 < levels_.size() && sigma > levels_[k].sigma) ++k;
  const Level& hi = levels_[k];
  const Level& lo = levels_[k - 1];
  if (sigma >= hi.sigma) return hi.bilinear(ab);
  const float t = k == 1 ? sigma / hi.sigma : std::log2(sigma / lo.sigma);
  return (1.0f - t) * lo.bilinear(ab) + t * hi.bilinear(ab);
}

float LtcTexture::fetch_sigma(const Ltc& ltc, const Vec3& o, const Vec3& e1, const Vec3& e2, Vec2* ab) {
  // The cosine configuration: the square transformed by M⁻¹ (eq. 15).
  const Mat3& m_inv = ltc.m_inv();
  const Vec3 oc = m_inv * o, e1c = m_inv * e1, e2c = m_inv * e2;
  const Vec3 nc = glm::cross(e1c, e2c);
  const float area = glm::length(nc);
  if (!(area > 0.0f) || !std::isfinite(area)) {
    *ab = Vec2(0.5f);
    return 4.0f;
  }
  // The orthogonal projection q of the shading point (the origin) on the plane, and its (a, b).
  const float r = glm::dot(oc, nc) / area;
  const Vec3 d = r * (nc / area) - oc;  // q − o
  const float g11 = glm::dot(e1c, e1c), g12 = glm::dot(e1c, e2c), g22 = glm::dot(e2c, e2c);
  const float det = area * area;  // g11 g22 − g12² = |e1 × e2|²
  const float d1 = glm::dot(d, e1c), d2 = glm::dot(d, e2c);
  *ab = Vec2((g22 * d1 - g12 * d2) / det, (g11 * d2 - g12 * d1) / det);
  return std::sqrt(r * r / (2.0f * area));
}

Rgb LtcTexture::fetch(const Ltc& ltc, const Vec3& o, const Vec3& e1, const Vec3& e2) const {
  Vec2 ab;
  const float sigma = fetch_sigma(ltc, o, e1, e2, &ab);
  return lookup(ab, sigma);
}

}  // namespace kozu
