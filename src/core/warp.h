// Warps from the unit square to common domains, each as the triplet sample / pdf / invert.
// Directions are in a local frame with +z as the pole; pdfs are per unit solid angle (or area).
#pragma once

#include "core/frame.h"
#include "core/math.h"

namespace kozu::warp {

// cos and sin of a in [-pi/4, pi/4] by Taylor polynomials (degrees 10 and 11): error < 2e-9,
// below float precision, without the range reduction of the library functions.
inline Vec2 cos_sin_quarter(float a) {
  const float a2 = a * a;
  const float c =
      1.0f + a2 * (-1.0f / 2 + a2 * (1.0f / 24 + a2 * (-1.0f / 720 + a2 * (1.0f / 40320 + a2 * (-1.0f / 3628800)))));
  const float s =
      a * (1.0f +
           a2 * (-1.0f / 6 + a2 * (1.0f / 120 + a2 * (-1.0f / 5040 + a2 * (1.0f / 362880 + a2 * (-1.0f / 39916800))))));
  return Vec2(c, s);
}

// Shirley & Chiu 1997 concentric map (square -> unit disk), area-preserving up to a constant.
// The polar angle is pi/4 * ratio (first case) or pi/2 - pi/4 * ratio (second case), so both need
// only cos/sin of an angle in [-pi/4, pi/4]; cos(pi/2 - a) = sin(a) swaps the pair.
inline Vec2 square_to_disk_concentric(const Vec2& u) {
  const Vec2 o = 2.0f * u - Vec2(1.0f);
  if (o.x == 0.0f && o.y == 0.0f) return Vec2(0.0f);
  if (std::abs(o.x) > std::abs(o.y)) {
    const Vec2 cs = cos_sin_quarter(kPiOver4 * (o.y / o.x));
    return o.x * cs;
  }
  const Vec2 cs = cos_sin_quarter(kPiOver4 * (o.x / o.y));
  return o.y * Vec2(cs.y, cs.x);
}
// The rim points (u on the square's edge) can land an ulp outside the unit circle: accept them.
inline float square_to_disk_concentric_pdf(const Vec2& p) { return glm::dot(p, p) <= 1.0f + 1e-6f ? kInvPi : 0.0f; }
inline Vec2 disk_concentric_to_square(const Vec2& p) {
  const float r = std::sqrt(p.x * p.x + p.y * p.y);
  float phi = std::atan2(p.y, p.x);
  if (phi < -kPiOver4) phi += kTwoPi;  // map to [-pi/4, 7pi/4)
  float a, b;
  if (phi < kPiOver4) {
    a = r;
    b = phi * a / kPiOver4;
  } else if (phi < 3.0f * kPiOver4) {
    b = r;
    a = -(phi - kPiOver2) * b / kPiOver4;
  } else if (phi < 5.0f * kPiOver4) {
    a = -r;
    b = (phi - kPi) * a / kPiOver4;
  } else {
    b = -r;
    a = -(phi - 3.0f * kPiOver2) * b / kPiOver4;
  }
  return Vec2(0.5f * (a + 1.0f), 0.5f * (b + 1.0f));
}

// Cosine-weighted hemisphere (Malley's method).
inline Vec3 square_to_cosine_hemisphere(const Vec2& u) {
  const Vec2 d = square_to_disk_concentric(u);
  return Vec3(d.x, d.y, safe_sqrt(1.0f - d.x * d.x - d.y * d.y));
}
inline float square_to_cosine_hemisphere_pdf(const Vec3& w) { return w.z > 0.0f ? w.z * kInvPi : 0.0f; }
inline Vec2 cosine_hemisphere_to_square(const Vec3& w) { return disk_concentric_to_square(Vec2(w.x, w.y)); }

// Uniform sphere by the cylinder (Archimedes) projection.
inline Vec3 square_to_uniform_sphere(const Vec2& u) {
  const float z = 1.0f - 2.0f * u.x;
  const float r = safe_sqrt(1.0f - z * z);
  const float phi = kTwoPi * u.y;
  return Vec3(r * std::cos(phi), r * std::sin(phi), z);
}
inline float square_to_uniform_sphere_pdf(const Vec3&) { return kInv4Pi; }
inline Vec2 uniform_sphere_to_square(const Vec3& w) {
  float phi = std::atan2(w.y, w.x);
  if (phi < 0.0f) phi += kTwoPi;
  return Vec2((1.0f - w.z) * 0.5f, phi * kInv2Pi);
}

inline Vec3 square_to_uniform_hemisphere(const Vec2& u) {
  const float z = u.x;
  const float r = safe_sqrt(1.0f - z * z);
  const float phi = kTwoPi * u.y;
  return Vec3(r * std::cos(phi), r * std::sin(phi), z);
}
inline float square_to_uniform_hemisphere_pdf(const Vec3& w) { return w.z >= 0.0f ? kInv2Pi : 0.0f; }
inline Vec2 uniform_hemisphere_to_square(const Vec3& w) {
  float phi = std::atan2(w.y, w.x);
  if (phi < 0.0f) phi += kTwoPi;
  return Vec2(w.z, phi * kInv2Pi);
}

// Uniform sphere and hemisphere by Marsaglia's method (G. Marsaglia 1972, "Choosing a Point from the
// Surface of a Sphere", Ann. Math. Statist. 43(2), 645-646), as derived in the
// "Marsagliaの方法" blog post of ushiostarfish's diary, 2018. (x1, x2) is uniform in the
// unit disk by rejection from [-1, 1]^2, so s = x1^2 + x2^2 is uniform on [0, 1) and (x1, x2) / sqrt(s) is
// a uniform azimuth, independent of s. For the sphere z = 1 - 2s is uniform on [-1, 1] (Archimedes), and
// the radius sqrt(1 - z^2) = 2 sqrt(s) sqrt(1 - s) cancels the normalisation of (x1, x2):
//   (x, y, z) = (2 x1 sqrt(1 - s), 2 x2 sqrt(1 - s), 1 - 2s).
// For the hemisphere z = 1 - s, radius sqrt(s) sqrt(2 - s):  (x, y, z) = (x1 sqrt(2 - s), x2 sqrt(2 - s), 1 - s).
// An attempt is accepted with probability pi/4, so a sample costs 4/pi attempts (8/pi random numbers) on
// average. The number of random numbers is not fixed, so these take a generator (any type with next_float()
// in [0, 1), e.g. Pcg32) instead of a point of the unit square; they cannot be inverted or stratified.
// A point (x1, x2) uniform in the unit disk by rejection from [-1, 1]^2; returns s = x1^2 + x2^2.
template <class Rng>
float marsaglia_disk_point(Rng& rng, float* x1, float* x2) {
  float s;
  do {
    *x1 = 2.0f * rng.next_float() - 1.0f;
    *x2 = 2.0f * rng.next_float() - 1.0f;
    s = *x1 * *x1 + *x2 * *x2;
  } while (s >= 1.0f);
  return s;
}

template <class Rng>
Vec3 sample_sphere_marsaglia(Rng& rng) {
  float x1, x2;
  const float s = marsaglia_disk_point(rng, &x1, &x2);
  const float scale = 2.0f * std::sqrt(1.0f - s);
  return Vec3(x1 * scale, x2 * scale, 1.0f - 2.0f * s);
}
inline float sample_sphere_marsaglia_pdf(const Vec3&) { return kInv4Pi; }

template <class Rng>
Vec3 sample_hemisphere_marsaglia(Rng& rng) {
  float x1, x2;
  const float s = marsaglia_disk_point(rng, &x1, &x2);
  const float scale = std::sqrt(2.0f - s);
  return Vec3(x1 * scale, x2 * scale, 1.0f - s);
}
inline float sample_hemisphere_marsaglia_pdf(const Vec3& w) { return w.z >= 0.0f ? kInv2Pi : 0.0f; }

// Uniform directions in the cone of half-angle acos(cos_max) around +z.
inline Vec3 square_to_uniform_cone(const Vec2& u, float cos_max) {
  const float cos_t = 1.0f - u.x * (1.0f - cos_max);
  const float sin_t = safe_sqrt(1.0f - cos_t * cos_t);
  const float phi = kTwoPi * u.y;
  return Vec3(sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t);
}
inline float square_to_uniform_cone_pdf(const Vec3& w, float cos_max) {
  return w.z >= cos_max ? 1.0f / (kTwoPi * (1.0f - cos_max)) : 0.0f;
}
inline Vec2 uniform_cone_to_square(const Vec3& w, float cos_max) {
  float phi = std::atan2(w.y, w.x);
  if (phi < 0.0f) phi += kTwoPi;
  return Vec2((1.0f - w.z) / (1.0f - cos_max), phi * kInv2Pi);
}

// Uniform barycentrics (b0, b1) on a triangle; Heitz 2019, "A Low-Distortion Map Between
// Triangle and Square", which keeps the stratification of the input points.
inline Vec2 square_to_uniform_triangle(const Vec2& u) {
  float b0, b1;
  if (u.x < u.y) {
    b0 = u.x / 2.0f;
    b1 = u.y - b0;
  } else {
    b1 = u.y / 2.0f;
    b0 = u.x - b1;
  }
  return Vec2(b0, b1);
}
inline Vec2 uniform_triangle_to_square(const Vec2& b) {
  if (b.y > b.x) {
    const float u0 = 2.0f * b.x;
    return Vec2(u0, b.y + b.x);
  }
  const float u1 = 2.0f * b.y;
  return Vec2(b.x + b.y, u1);
}

// Uniform 1D tent on [-r, r] (used for pixel reconstruction filters).
inline float sample_tent(float u, float r) {
  if (u < 0.5f) return -r + r * std::sqrt(2.0f * u);
  return r - r * std::sqrt(2.0f - 2.0f * u);
}

}  // namespace kozu::warp
