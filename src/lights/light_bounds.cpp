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

float LightBounds::importance(const Vec3& p, const Vec3& n) const {
  if (!(phi > 0.0f)) return 0.0f;
  const Vec3 c = centre();
  const Vec3 to_p = p - c;
  const float dist2 = glm::dot(to_p, to_p);
  const float r2 = 0.25f * glm::dot(hi - lo, hi - lo);  // the squared radius of the box's bounding sphere
  // θu: the half-angle the bounding sphere subtends at p; π inside it, where every direction may hold a light.
  float theta_u = 0.0f;
  if (r2 > 0.0f) theta_u = dist2 > r2 ? std::asin(std::min(1.0f, std::sqrt(r2 / dist2))) : kPi;
  float theta = 0.0f;  // between the axis and the direction from the cluster to p (0 at the centre itself)
  Vec3 w(0.0f);
  if (dist2 > 0.0f) {
    w = to_p / std::sqrt(dist2);
    theta = safe_acos(glm::dot(cone.axis, w));
  }
  const float theta_p = std::max(0.0f, theta - cone.theta_o - theta_u);
  // A margin over the float error of the angles: a light that reaches p by a hair must keep a positive importance.
  if (theta_p > cone.theta_e + 1e-3f) return 0.0f;
  float cos_receiver = 1.0f;  // in a medium, or at a surface seen from within θu of its plane's normal
  if (glm::dot(n, n) > 0.0f && dist2 > 0.0f) {
    // |cos|: a transmitting surface takes light from both sides.
    const float theta_i = safe_acos(std::abs(glm::dot(n, w)));
    cos_receiver = std::cos(std::max(0.0f, theta_i - theta_u));
  }
  const float d2 = std::max({dist2, r2, 1e-12f});
  // A cone wider than a hemisphere (a spot's falloff beyond 90°) emits past θ' = π/2, where cos θ' ≤ 0: a small
  // floor keeps such lights' importance positive wherever they reach.
  const float cos_emitter = std::max(std::cos(theta_p), 1e-3f);
  return phi * cos_emitter * cos_receiver / d2;
}

}  // namespace kozu
