#include "lights/light_bounds.h"

#include <algorithm>
#include <cmath>

namespace kozu {

DirectionCone DirectionCone::merge(const DirectionCone& a_in, const DirectionCone& b_in) {
  // Conty Estevez & Kulla 2018, Algorithm 1: widen the wider cone just enough to hold the other.
  const bool swap = b_in.theta_o > a_in.theta_o;
  const DirectionCone& a = swap ? b_in : a_in;
  const DirectionCone& b = swap ? a_in : b_in;
  const float theta_d = safe_acos(glm::dot(a.axis, b.axis));
  const float theta_e = std::max(a.theta_e, b.theta_e);
  if (std::min(theta_d + b.theta_o, kPi) <= a.theta_o) return DirectionCone{a.axis, a.theta_o, theta_e};
  const float theta_o = 0.5f * (a.theta_o + theta_d + b.theta_o);
  if (theta_o >= kPi) return DirectionCone{a.axis, kPi, theta_e};
  // Turn a's axis towards b's by θo − θo(a), in the plane of the two (any plane when they are opposite).
  Vec3 perp = b.axis - a.axis * glm::dot(a.axis, b.axis);
  const float len = glm::length(perp);
  if (len > 1e-6f) {
    perp /= len;
  } else {
    const Vec3 helper = std::abs(a.axis.x) < 0.9f ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
    perp = glm::normalize(glm::cross(a.axis, helper));
  }
  const float theta_r = theta_o - a.theta_o;
  const Vec3 axis = glm::normalize(std::cos(theta_r) * a.axis + std::sin(theta_r) * perp);
  return DirectionCone{axis, theta_o, theta_e};
}

LightBounds LightBounds::merge(const LightBounds& a, const LightBounds& b) {
  if (!(a.phi > 0.0f)) return b;
  if (!(b.phi > 0.0f)) return a;
  LightBounds m;
  m.lo = glm::min(a.lo, b.lo);
  m.hi = glm::max(a.hi, b.hi);
  m.cone = DirectionCone::merge(a.cone, b.cone);
  m.phi = a.phi + b.phi;
  return m;
}

LightCluster LightCluster::from(const LightBounds& b) {
  LightCluster c;
  c.centre = b.centre();
  c.r2 = 0.25f * glm::dot(b.hi - b.lo, b.hi - b.lo);
  c.axis = b.cone.axis;
  c.cos_o = std::cos(b.cone.theta_o);
  c.sin_o = std::sin(b.cone.theta_o);
  c.cos_e = std::cos(std::min(b.cone.theta_e + 1e-3f, kPi));
  c.phi = b.phi;
  return c;
}

namespace {
// cos(a − b) for a ≥ b, given both angles' cosines and sines; 1 (the difference clamped at 0) when a < b.
inline float cos_difference(float cos_a, float sin_a, float cos_b, float sin_b) {
  return cos_a > cos_b ? 1.0f : cos_a * cos_b + sin_a * sin_b;
}
inline float sin_from_cos(float c) { return std::sqrt(std::max(0.0f, 1.0f - c * c)); }
}  // namespace

float LightCluster::importance(const Vec3& p, const Vec3& n) const {
  if (!(phi > 0.0f)) return 0.0f;
  const Vec3 to_p = p - centre;
  const float dist2 = glm::dot(to_p, to_p);
  // θu, the half-angle the bounding sphere subtends at p: sin θu = r / d; inside it every direction may hold a light
  // (θu = π), and so does the centre itself.
  if (dist2 <= r2 || !(dist2 > 0.0f)) return phi / std::max(r2, 1e-12f);  // θ' = 0 and θ'_i = 0
  const float sin_u2 = r2 / dist2;
  const float sin_u = std::sqrt(sin_u2), cos_u = std::sqrt(1.0f - sin_u2);
  const Vec3 w = to_p * (1.0f / std::sqrt(dist2));
  // θ' = max(0, θ − θo − θu): two clamped subtractions.
  const float cos_w = glm::dot(axis, w);
  const float sin_w = sin_from_cos(cos_w);
  const float cos_wo = cos_difference(cos_w, sin_w, cos_o, sin_o);
  const float sin_wo = cos_w > cos_o ? 0.0f : sin_w * cos_o - cos_w * sin_o;
  const float cos_p = cos_difference(cos_wo, sin_wo, cos_u, sin_u);
  if (cos_p < cos_e) return 0.0f;  // θ' > θe: no light of the cluster emits towards p
  float cos_receiver = 1.0f;       // in a medium
  if (glm::dot(n, n) > 0.0f) {
    // |cos|: a transmitting surface takes light from both sides.
    const float cos_i = std::abs(glm::dot(n, w));
    cos_receiver = cos_difference(cos_i, sin_from_cos(cos_i), cos_u, sin_u);
  }
  // A cone wider than a hemisphere (a spot's falloff beyond 90°) emits past θ' = π/2, where cos θ' ≤ 0: a small
  // floor keeps such lights' importance positive wherever they reach.
  return phi * std::max(cos_p, 1e-3f) * cos_receiver / std::max(dist2, 1e-12f);
}

}  // namespace kozu
