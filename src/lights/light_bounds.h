// Bounds of a light's emission for the light hierarchy (lights/light_tree.h): where it emits from (a box), in which
// directions (an orientation cone: axis, θo the spread of the emitters' normals, θe the spread of emission about
// each normal) and how much (its power Φ), and the importance of such a cluster seen from a point.
//
// Conty Estevez & Kulla 2018, "Importance Sampling of Many Lights with Adaptive Tree Splitting": the orientation
// bounds (§4.1, Fig. 3), their union (Algorithm 1) and the importance of a cluster (eq. 3),
//   I(p) = Φ |cos θ'_i| cos θ' / d²,   θ' = max(0, θ − θo − θu),   0 when θ' ≥ θe,
// where θ is the angle between the axis and the direction from the cluster to p, θu the half-angle the box subtends
// at p, θ'_i = max(0, θ_i − θu) with θ_i the angle at the receiver's normal (1 in a medium), and d the distance
// to the box's centre, clamped below at half the box's diagonal so that a point inside a cluster does not make it
// infinitely important. Every term bounds its factor from above, so a cluster's importance is 0 only where no light
// in it can reach p: the selection stays unbiased.
#pragma once

#include "core/math.h"

namespace kozu {

struct DirectionCone {
  Vec3 axis{0.0f, 0.0f, 1.0f};
  float theta_o = 0.0f;  // the normals lie within θo of the axis
  float theta_e = 0.0f;  // each emits within θe of its normal

  // The smallest cone this representation holds with both (Algorithm 1).
  static DirectionCone merge(const DirectionCone& a, const DirectionCone& b);
};

struct LightBounds {
  Vec3 lo{0.0f}, hi{0.0f};
  DirectionCone cone;
  float phi = 0.0f;       // intensity scale (Light::bounds); for an infinite light its irradiance
  bool infinite = false;  // environment or distant light: no box, no cone

  Vec3 centre() const { return 0.5f * (lo + hi); }
  static LightBounds merge(const LightBounds& a, const LightBounds& b);
};

// LightBounds prepared for eq. (3) at every traversal step: the box as its bounding sphere, the cone's angles as
// cosines and sines, so that the importance takes square roots and products only (the angle differences by the
// subtraction formulas) instead of four inverse and direct trigonometric functions.
struct LightCluster {
  Vec3 centre{0.0f};
  float r2 = 0.0f;  // the squared radius of the box's bounding sphere
  Vec3 axis{0.0f, 0.0f, 1.0f};
  float cos_o = 1.0f, sin_o = 0.0f;
  float cos_e = 1.0f;  // cos(θe + a margin over the float error of the angles, 10⁻³)
  float phi = 0.0f;

  static LightCluster from(const LightBounds& b);
  // The importance of the cluster seen from p, whose surface normal is n (zero in a medium): eq. (3) above.
  float importance(const Vec3& p, const Vec3& n) const;
};

}  // namespace kozu
