// Linearly transformed cosines (LTC): a spherical distribution D made by transforming the clamped cosine D_o
// with a 3x3 matrix M, with closed-form evaluation, exact sampling and closed-form integrals over polygons.
//
// Citation: Heitz, Dupuy, Hill, Neubelt 2016, "Real-Time Polygonal-Light Shading with Linearly Transformed
// Cosines", ACM TOG 35(4), SIGGRAPH 2016.
//   D(ω)   = D_o(M⁻¹ω / ‖M⁻¹ω‖) |M⁻¹| / ‖M⁻¹ω‖³                   eq. (1), Jacobian eqs. (16)–(19)
//   D_o(ω) = max(0, z) / π                                        eq. (4)
//   ∫ D dω = ∫ D_o dω_o = 1                                       eq. (2)
//   ∫_P D dω = ∫_{P_o} D_o dω_o = E(P_o),  P_o = M⁻¹ P           eqs. (3), (10)
//   E(p_1 … p_n) = 1/(2π) Σ acos(⟨p_i, p_j⟩) ⟨p_i × p_j / ‖p_i × p_j‖, z⟩,  j = i + 1 mod n   eq. (11)
//   sampling: ω_o ~ D_o, ω = M ω_o / ‖M ω_o‖; its density is D(ω) exactly     §3.2 "Importance Sampling"
// Eq. (11) holds for a polygon in the upper hemisphere: P_o is clipped to z >= 0 first (§5.1). kozu evaluates the
// edge terms in double: acos of a dot product near 1 (a small or distant polygon's short edges) loses all its
// digits in float (tests/lights/test_ltc.cpp measures it).
#pragma once

#include "core/math.h"

#include <span>

namespace kozu {

class Ltc {
 public:
  // The identity: D = D_o, the clamped cosine.
  Ltc() = default;
  // D from M; M must be invertible.
  explicit Ltc(const Mat3& m);
  // D from M⁻¹ (what the fitted tables store, §4 "Representation and Storage").
  static Ltc from_inverse(const Mat3& m_inv);

  // D(ω) for a unit ω, eq. (1).
  float eval(const Vec3& w) const;
  // A direction distributed as D, from u in [0, 1)².
  Vec3 sample(const Vec2& u) const;
  // The density of sample(): D itself.
  float pdf(const Vec3& w) const { return eval(w); }

  // ∫_P D dω for the polygon P of 3 to kMaxVertices vertices (points relative to the shading point, in D's
  // frame, in order; either winding: the integral is of the solid angle, not signed), eq. (3), (11).
  float integrate_polygon(std::span<const Vec3> vertices) const;

  const Mat3& m() const { return m_; }
  const Mat3& m_inv() const { return m_inv_; }
  float det_inv() const { return det_inv_; }  // |M⁻¹|

  static constexpr int kMaxVertices = 8;

 private:
  Mat3 m_{1.0f}, m_inv_{1.0f};
  float det_inv_ = 1.0f;  // |M⁻¹|
};

// E(P) of eq. (11): the integral of the clamped cosine D_o over the spherical polygon of the points p (not
// necessarily unit, not necessarily above the horizon: the polygon is clipped to z >= 0). Its absolute value:
// a polygon wound either way gives the same.
double clamped_cosine_polygon_integral(std::span<const Vec3> p);

}  // namespace kozu
