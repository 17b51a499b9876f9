// Rays and the robust origin offset used to leave a surface without re-hitting it.
#pragma once

#include "core/math.h"

namespace kozu {

struct Ray {
  Vec3 o;
  Vec3 d;
  float tmax = kInfinity;
  Vec3 at(float t) const { return o + t * d; }
};

// Moves p off the surface along the geometric normal n, on the side n points to.
// Wächter & Binder 2019, "A Fast and Robust Method for Avoiding Self-Intersection"
// (Ray Tracing Gems, ch. 6): an offset of a fixed number of float ULPs, scaled for points near 0.
inline float offset_component(float p, float n) {
  constexpr float kOrigin = 1.0f / 32.0f;
  constexpr float kFloatScale = 1.0f / 65536.0f;
  constexpr float kIntScale = 256.0f;
  const int32_t of_i = static_cast<int32_t>(kIntScale * n);
  const int32_t bits = static_cast<int32_t>(float_as_bits(p)) + (p < 0.0f ? -of_i : of_i);
  const float p_i = bits_as_float(static_cast<uint32_t>(bits));
  return std::abs(p) < kOrigin ? p + kFloatScale * n : p_i;  // selects, no branches
}

inline Vec3 offset_ray_origin(const Vec3& p, const Vec3& n) {
  return Vec3(offset_component(p.x, n.x), offset_component(p.y, n.y), offset_component(p.z, n.z));
}

// p moved along the unit normal n past an error bound `error` (the surface may lie anywhere within it), then
// past its own rounding.
inline Vec3 offset_point(const Vec3& p, const Vec3& n, float error) {
  return offset_ray_origin(error > 0.0f ? p + error * n : p, n);
}

}  // namespace kozu
