#include "media/equiangular.h"

#include <cmath>
#include <limits>
#include <numbers>

namespace kozu {

Equiangular::Equiangular(const Vec3& o, const Vec3& d, float a, float b, const Vec3& c) : a_(a), b_(b) {
  const glm::dvec3 oc = glm::dvec3(c) - glm::dvec3(o);
  const glm::dvec3 dd(d);
  delta_ = glm::dot(oc, dd);
  dist_ = glm::length(oc - delta_ * dd);
  if (!(dist_ > 1e-6 * glm::length(oc)) || !(b > a) || !std::isfinite(dist_)) return;
  theta_a_ = std::atan2(double(a) - delta_, dist_);
  theta_b_ = std::isinf(b) ? 0.5 * std::numbers::pi : std::atan2(double(b) - delta_, dist_);
  valid_ = theta_b_ > theta_a_;
}

float Equiangular::sample(float u) const {
  const double t = delta_ + dist_ * std::tan(theta_a_ + double(u) * (theta_b_ - theta_a_));
  // tan rounds past the interval's ends for u at 0 or near 1.
  return std::clamp(static_cast<float>(t), a_, std::nextafter(b_, a_));
}

float Equiangular::pdf(float t) const {
  if (!valid_ || !(t >= a_ && t < b_)) return 0.0f;
  const double x = double(t) - delta_;
  return static_cast<float>(dist_ / ((theta_b_ - theta_a_) * (dist_ * dist_ + x * x)));
}

}  // namespace kozu
