// equiangular: distances along a ray towards a point, drawn in proportion to 1/r² as seen from that point (Kulla &
// Fajardo 2012, "Importance Sampling Techniques for Path Tracing in Participating Media", §4.1 eqs. 5–7). Light
// sampled from a point of the ray falls off as 1/r² from the light; distances drawn this way follow it, where free
// flights (media/homogeneous_flight.h) follow the transmittance instead. The path tracer weighs the two by MIS.
//
// For the ray o + t d (d a unit vector) over [a, b) and the point c: Δ = (c − o)·d is the ray parameter closest to c,
// D = |c − o − Δ d| the distance of c from the ray's line, and θ(t) = atan((t − Δ) / D):
//   pdf(t) = D / ((θ_b − θ_a) (D² + (t − Δ)²)),    t(u) = Δ + D tan(θ_a + u (θ_b − θ_a)).
// b may be infinite (θ_b = π/2). Where c lies on the line (D below 1e-6 of |c − o|) the density is a spike that
// floats cannot represent: valid() is false, and the caller samples distances by free flight alone.
// Computed in double: tan near ±π/2 and D² + (t − Δ)² for D ≪ |t − Δ| lose too much in float. θ_b − θ_a comes from one
// atan2 and a sample from one sine and cosine (equiangular.cpp): the homogeneous medium box spent 5 % of its time
// in the two atan2 and the tan this took before (docs/performance.md).
#pragma once

#include "core/math.h"

namespace kozu {

class Equiangular {
 public:
  Equiangular() = default;  // not valid
  Equiangular(const Vec3& o, const Vec3& d, float a, float b, const Vec3& c);
  bool valid() const { return valid_; }
  // The distance for u in [0, 1), in [a, b) (below b by at least one float step).
  float sample(float u) const;
  // The density of t per unit length; 0 outside [a, b).
  float pdf(float t) const;

 private:
  double delta_ = 0, dist_ = 0;
  double xa_ = 0;     // a − Δ
  double theta_ = 0;  // θ_b − θ_a
  float a_ = 0, b_ = 0;
  bool valid_ = false;
};

}  // namespace kozu
