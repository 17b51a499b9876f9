#include "materials/detail_normal_blend.h"

#include <algorithm>
#include <cmath>

namespace kozu {

namespace {

Vec3 unit(const Vec3& v) {
  const float len2 = glm::dot(v, v);
  return len2 > 0.0f ? v / std::sqrt(len2) : Vec3(0.0f, 0.0f, 1.0f);
}

}  // namespace

Vec3 blend_xy(const Vec3& base, const Vec3& detail) {
  const Vec3 b = unit(base), d = unit(detail);
  // Chan 2018 Algorithm 4: the offsets add, Z is recomputed from them.
  float x = b.x + d.x, y = b.y + d.y;
  const float r2 = x * x + y * y;
  if (r2 > 1.0f) {  // beyond the unit disc: onto the horizon (see the header)
    const float s = 1.0f / std::sqrt(r2);
    return Vec3(x * s, y * s, 0.0f);
  }
  return Vec3(x, y, std::sqrt(std::max(0.0f, 1.0f - r2)));
}

Vec3 blend_rnm(const Vec3& base, const Vec3& detail) {
  const Vec3 b = unit(base), d = unit(detail);
  // Barré-Brisebois & Hill 2012: t = b + z, u = d with x, y negated; r = t (t · u) / t_z − u is d rotated by the
  // shortest arc taking +z to b.
  const Vec3 t(b.x, b.y, b.z + 1.0f);
  if (t.z < 1e-6f) return b;  // b = −z: no unique shortest arc
  const Vec3 u(-d.x, -d.y, d.z);
  return unit(t * (glm::dot(t, u) / t.z) - u);
}

}  // namespace kozu
