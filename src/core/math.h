// Basic math types and helpers shared by every kozu module.
// Geometry and shading run in single precision (Embree's precision); accumulation
// of pixel estimates is done in double precision by the film.
#pragma once

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace kozu {

using Vec2 = glm::vec2;
using Vec3 = glm::vec3;
using Vec4 = glm::vec4;
using Vec2i = glm::ivec2;
using Vec3d = glm::dvec3;
using Mat3 = glm::mat3;
using Mat4 = glm::mat4;

inline constexpr float kPi = 3.14159265358979323846f;
inline constexpr float kTwoPi = 2.0f * kPi;
inline constexpr float kInvPi = 0.31830988618379067154f;
inline constexpr float kInv2Pi = 0.15915494309189533577f;
inline constexpr float kInv4Pi = 0.07957747154594766788f;
inline constexpr float kPiOver2 = 1.57079632679489661923f;
inline constexpr float kPiOver4 = 0.78539816339744830962f;
inline constexpr float kInfinity = std::numeric_limits<float>::infinity();
// Largest float strictly below 1: samples live in [0, 1).
inline constexpr float kOneMinusEpsilon = 0x1.fffffep-1f;

template <typename T>
constexpr T sqr(T x) {
  return x * x;
}

inline float safe_sqrt(float x) { return std::sqrt(std::max(x, 0.0f)); }
inline float safe_acos(float x) { return std::acos(std::clamp(x, -1.0f, 1.0f)); }
inline float safe_asin(float x) { return std::asin(std::clamp(x, -1.0f, 1.0f)); }

inline float max_component(const Vec3& v) { return std::max(v.x, std::max(v.y, v.z)); }
inline float min_component(const Vec3& v) { return std::min(v.x, std::min(v.y, v.z)); }
inline float average(const Vec3& v) { return (v.x + v.y + v.z) * (1.0f / 3.0f); }

inline bool is_finite(float x) { return std::isfinite(x); }
inline bool is_finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Squared length without the sqrt, used for distances and normalisation checks.
inline float length_sq(const Vec3& v) { return glm::dot(v, v); }

inline uint32_t float_as_bits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return u;
}
inline float bits_as_float(uint32_t u) {
  float f;
  std::memcpy(&f, &u, sizeof f);
  return f;
}

// atan2(y, x) in [-pi, pi] to within 5e-7 rad (the fit's 1.2e-7 and float rounding; std::atan2f is within one ulp,
// up to 2.4e-7) at a sixth of its cost (bench_core BM_Atan2: 3.0 ns against 19.7). The octant's ratio t = min / max
// in [0, 1], atan t by an odd polynomial of degree 17 fitted to atan on [0, 1] (minimax, by Lawson's iteration), then
// the octant's symmetries. For maps from directions to image coordinates (an environment's longitude, the guiding
// quadtrees' cylinder), where std::atan2f was a tenth of a lookup. For finite arguments; atan2(±0, ±0) as
// std::atan2's; NaN in, NaN out.
inline float fast_atan2(float y, float x) {
  if (std::isnan(x) || std::isnan(y)) return x + y;
  const float ax = std::abs(x), ay = std::abs(y);
  const float hi = std::max(ax, ay), lo = std::min(ax, ay);
  const float t = hi > 0.0f ? lo / hi : 0.0f;  // 0 for (0, 0)
  const float s = t * t;
  float r = 0.0024567204527556896f;
  r = r * s - 0.01440134271979332f;
  r = r * s + 0.039781197905540466f;
  r = r * s - 0.07234855741262436f;
  r = r * s + 0.10498945415019989f;
  r = r * s - 0.14161229133605957f;
  r = r * s + 0.19985906779766083f;
  r = r * s - 0.33332598209381104f;
  r = r * s + 0.9999998807907104f;
  r *= t;
  if (ay > ax) r = 1.57079632679489662f - r;
  if (std::signbit(x)) r = kPi - r;
  return std::copysign(r, y);
}

// acos(y) in [0, pi] as fast_atan2(sin, y), sin = sqrt((1 - y)(1 + y)) without 1 - y²'s cancellation near ±1;
// y outside [-1, 1] clamps as safe_acos does.
inline float fast_acos(float y) { return fast_atan2(safe_sqrt((1.0f - y) * (1.0f + y)), std::clamp(y, -1.0f, 1.0f)); }

// Power heuristic with beta = 2 (Veach 1997, eq. 9.13) for one sample of each strategy.
inline float power_heuristic(float pdf_a, float pdf_b) {
  const float a = pdf_a * pdf_a;
  const float b = pdf_b * pdf_b;
  if (std::isinf(a)) return 1.0f;
  return a + b > 0.0f ? a / (a + b) : 0.0f;
}

}  // namespace kozu
