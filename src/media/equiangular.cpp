#include "media/equiangular.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace kozu {

Equiangular::Equiangular(const Vec3& o, const Vec3& d, float a, float b, const Vec3& c) : a_(a), b_(b) {
  const glm::dvec3 oc = glm::dvec3(c) - glm::dvec3(o);
  const glm::dvec3 dd(d);
  delta_ = glm::dot(oc, dd);
  dist_ = glm::length(oc - delta_ * dd);
  if (!(dist_ > 1e-6 * glm::length(oc)) || !(b > a) || !std::isfinite(dist_)) return;
  // θ_b − θ_a as the angle between (D, a − Δ) and (D, b − Δ), seen from c: one atan2 instead of two, and exact
  // where the segment subtends a small angle (no difference of two nearly equal angles). For b infinite the second
  // vector is the line's direction (0, 1).
  xa_ = double(a) - delta_;
  theta_ = std::isinf(b) ? std::atan2(dist_, xa_)
                         : std::atan2(dist_ * (double(b) - double(a)), dist_ * dist_ + xa_ * (double(b) - delta_));
  valid_ = theta_ > 0.0;
}

float Equiangular::sample(float u) const {
  // tan(θ_a + φ) with φ = u (θ_b − θ_a), by rotating (D, a − Δ) by φ: tan θ_a = (a − Δ) / D needs no atan.
  const double phi = double(u) * theta_;
  const double s = std::sin(phi), c = std::cos(phi);
  const double den = dist_ * c - xa_ * s;
  // Past θ = π/2 (b infinite, u rounding to 1) the point is infinitely far: the segment's far end.
  if (!(den > 0.0)) return std::nextafter(b_, a_);
  const double t = delta_ + dist_ * (xa_ * c + dist_ * s) / den;
  // Rounding takes t past the interval's ends for u at 0 or near 1.
  return std::clamp(static_cast<float>(t), a_, std::nextafter(b_, a_));
}

float Equiangular::pdf(float t) const {
  if (!valid_ || !(t >= a_ && t < b_)) return 0.0f;
  const double x = double(t) - delta_;
  return static_cast<float>(dist_ / (theta_ * (dist_ * dist_ + x * x)));
}

}  // namespace kozu
