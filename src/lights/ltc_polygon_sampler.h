// An LTC restricted to a polygon light: directions on the polygon P with a density close to D / ∫_P D, so that
// every sample lands on the light (Ltc::sample draws over the whole sphere and misses P with probability
// 1 − ∫_P D, which in a penumbra leaves "direct": "ltc" without its LTC strategy; integrators/path.cpp).
//
// Method: in the cosine configuration (Heitz et al. 2016 eq. 3: the polygon transformed by M⁻¹, where D is the clamped
// cosine D_o) the polygon's triangles are clipped to the upper hemisphere and sampled uniformly by solid angle,
// then the direction is transformed back by M. The density is therefore exact and cheap:
//   p(ω) = J(ω) / Ω',  J(ω) = |M⁻¹| / ‖M⁻¹ω‖³ (Heitz et al. 2016 eq. 1's Jacobian), Ω' = the solid angle of the clipped
//   M⁻¹P,
// and p / (D / ∫_P D) = cos θ' / (the mean of cos θ' over M⁻¹P): 1 for a small light, between 0 and 2 for a large one.
//
// Citations: Heitz, Dupuy, Hill, Neubelt 2016, "Real-Time Polygonal-Light Shading with Linearly Transformed
// Cosines", ACM TOG 35(4), eqs. (1), (3) and
// §5.1 (clipping); Arvo 1995, "Stratified Sampling of Spherical Triangles" (the sampling of one spherical
// triangle, in double); Van Oosterom & Strackee 1983 (a triangle's solid angle, tan(Ω/2) = |a·(b×c)| /
// (1 + a·b + b·c + c·a), stable for small triangles).
#pragma once

#include "core/ltc.h"

#include <array>
#include <span>

namespace kozu {

class LtcPolygonSampler {
 public:
  // Up to this many planar triangles (an 8-corner polygon's triangulation); each clips to at most two.
  static constexpr int kMaxTriangles = Ltc::kMaxVertices - 2;
  // Below this solid angle of the clipped M⁻¹P the sampler is not used (valid() is false): such a light is all but
  // a point to the lobe, and sampling it by area is already proportional to D.
  static constexpr double kMinSolidAngle = 1e-7;

  // triangles: the polygon's triangulation, corners relative to the shading point, in the LTC's frame.
  LtcPolygonSampler(const Ltc& ltc, std::span<const std::array<Vec3, 3>> triangles);

  bool valid() const { return solid_angle_ >= kMinSolidAngle; }
  // Ω', the solid angle of the clipped M⁻¹P.
  double solid_angle() const { return solid_angle_; }
  // A unit direction on P (valid() only).
  Vec3 sample(const Vec2& u) const;
  // The density of sample() at a unit direction w on P: J(w) / Ω', 0 where M⁻¹w lies below the horizon.
  float pdf(const Vec3& w) const;

 private:
  const Ltc* ltc_;
  struct Spherical {
    Vec3d a, b, c;  // unit corners in the cosine configuration
    double solid_angle;
  };
  std::array<Spherical, 2 * kMaxTriangles> tri_;
  int n_ = 0;
  double solid_angle_ = 0.0;
};

}  // namespace kozu
