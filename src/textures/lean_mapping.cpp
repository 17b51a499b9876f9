#include "textures/lean_mapping.h"

#include <algorithm>
#include <cmath>

namespace kozu {

namespace {
constexpr double kPiD = 3.14159265358979323846;
}  // namespace

void LeanMoments::add(const Vec3& n) {
  const double nz = std::max<double>(n.z, 1e-4);
  const double x = -n.x / nz, y = -n.y / nz;
  b[0] += x;
  b[1] += y;
  m[0] += x * x;
  m[1] += y * y;
  m[2] += x * y;
  count += 1;
}

void LeanMoments::add(const LeanMoments& o) {
  for (int i = 0; i < 2; ++i) b[i] += o.b[i];
  for (int i = 0; i < 3; ++i) m[i] += o.m[i];
  count += o.count;
}

LeanLobe::LeanLobe(const LeanMoments& s, double base_alpha) {
  const double c = std::max(s.count, 1.0);
  bx_ = s.b[0] / c;
  by_ = s.b[1] / c;
  // Olano & Baker 2010 eq. (9): Σ = M − B Bᵀ plus the base lobe's variance (Beckmann: σ₀² = α² / 2 a slope axis).
  const double s0 = 0.5 * base_alpha * base_alpha;
  sxx_ = std::max(s.m[0] / c - bx_ * bx_, 0.0) + s0;
  syy_ = std::max(s.m[1] / c - by_ * by_, 0.0) + s0;
  sxy_ = s.m[2] / c - bx_ * by_;
  // Keep Σ positive definite against rounding.
  const double limit = 0.999 * std::sqrt(sxx_ * syy_);
  sxy_ = std::clamp(sxy_, -limit, limit);
  det_ = sxx_ * syy_ - sxy_ * sxy_;
  lxx_ = std::sqrt(sxx_);
  lyx_ = sxy_ / lxx_;
  lyy_ = std::sqrt(std::max(syy_ - lyx_ * lyx_, 1e-300));
}

double LeanLobe::D(const Vec3& m) const {
  if (m.z <= 0.0f) return 0.0;
  const double x = -m.x / m.z - bx_, y = -m.y / m.z - by_;
  // The slope density P(x̃, ỹ) = N(B, Σ), over solid angle: P / cos⁴θ.
  const double q = (syy_ * x * x - 2.0 * sxy_ * x * y + sxx_ * y * y) / det_;
  const double cos2 = double(m.z) * m.z;
  return std::exp(-0.5 * q) / (2.0 * kPiD * std::sqrt(det_) * cos2 * cos2);
}

double LeanLobe::lambda(const Vec3& w) const {
  const double r2 = double(w.x) * w.x + double(w.y) * w.y;
  if (r2 <= 0) return 0;
  if (w.z == 0.0f) return INFINITY;
  // The slope variance along w's azimuth, and Beckmann's Λ for α² = 2 σ².
  const double var = (sxx_ * w.x * w.x + 2.0 * sxy_ * w.x * w.y + syy_ * w.y * w.y) / r2;
  const double a = std::abs(w.z) / std::sqrt(2.0 * var * r2);  // 1 / (α tan θ)
  if (a >= 4.5) return 0;
  return 0.5 * (std::exp(-a * a) / (a * 1.7724538509055160) - std::erfc(a));
}

Vec3 LeanLobe::sample(double u1, double u2) const {
  // Box–Muller: two independent unit normals, coloured by the Cholesky factor.
  const double r = std::sqrt(-2.0 * std::log(std::max(1.0 - u1, 1e-300)));
  const double g1 = r * std::cos(2.0 * kPiD * u2), g2 = r * std::sin(2.0 * kPiD * u2);
  const double x = bx_ + lxx_ * g1, y = by_ + lyx_ * g1 + lyy_ * g2;
  // Slopes (x̃, ỹ) = (−m_x / m_z, −m_y / m_z): pdf over slopes P; over normals P / cos³θ = D cos θ.
  const double inv = 1.0 / std::sqrt(1.0 + x * x + y * y);
  return Vec3(static_cast<float>(-x * inv), static_cast<float>(-y * inv), static_cast<float>(inv));
}

Vec3 LeanLobe::mean_normal() const {
  return glm::normalize(Vec3(static_cast<float>(-bx_), static_cast<float>(-by_), 1.0f));
}

}  // namespace kozu
