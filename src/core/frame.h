// Orthonormal frame around a unit vector; local coordinates have the normal on +z.
// Construction follows Duff et al. 2017, "Building an Orthonormal Basis, Revisited" (JCGT 6(1)).
#pragma once

#include "core/math.h"

namespace kozu {

// The vectors s, t that complete the unit vector n to a right-handed orthonormal basis (s, t, n), branch-free
// (Duff et al. 2017, Listing 3), in the precision of V (glm::vec3 or glm::dvec3).
template <typename V>
void orthonormal_basis(const V& n, V& s, V& t) {
  using T = typename V::value_type;
  const T sign = std::copysign(T(1), n.z);
  const T a = T(-1) / (sign + n.z);
  const T b = n.x * n.y * a;
  s = V(T(1) + sign * n.x * n.x * a, sign * b, -sign * n.x);
  t = V(b, sign + n.y * n.y * a, -n.y);
}

struct Frame {
  Vec3 s, t, n;

  Frame() : s(1, 0, 0), t(0, 1, 0), n(0, 0, 1) {}
  Frame(const Vec3& s_, const Vec3& t_, const Vec3& n_) : s(s_), t(t_), n(n_) {}

  explicit Frame(const Vec3& normal) : n(normal) { orthonormal_basis(n, s, t); }

  Vec3 to_local(const Vec3& v) const { return Vec3(glm::dot(v, s), glm::dot(v, t), glm::dot(v, n)); }
  Vec3 to_world(const Vec3& v) const { return s * v.x + t * v.y + n * v.z; }
};

// Spherical-coordinate helpers for local directions (normal = +z).
inline float cos_theta(const Vec3& w) { return w.z; }
inline float abs_cos_theta(const Vec3& w) { return std::abs(w.z); }
inline float cos2_theta(const Vec3& w) { return w.z * w.z; }
inline float sin2_theta(const Vec3& w) { return std::max(0.0f, 1.0f - w.z * w.z); }
inline float sin_theta(const Vec3& w) { return std::sqrt(sin2_theta(w)); }
inline float tan2_theta(const Vec3& w) { return sin2_theta(w) / cos2_theta(w); }
inline float cos_phi(const Vec3& w) {
  const float st = sin_theta(w);
  return st == 0.0f ? 1.0f : std::clamp(w.x / st, -1.0f, 1.0f);
}
inline float sin_phi(const Vec3& w) {
  const float st = sin_theta(w);
  return st == 0.0f ? 0.0f : std::clamp(w.y / st, -1.0f, 1.0f);
}
inline bool same_hemisphere(const Vec3& a, const Vec3& b) { return a.z * b.z > 0.0f; }

inline Vec3 spherical_direction(float sin_t, float cos_t, float phi) {
  return Vec3(std::clamp(sin_t, -1.0f, 1.0f) * std::cos(phi), std::clamp(sin_t, -1.0f, 1.0f) * std::sin(phi),
              std::clamp(cos_t, -1.0f, 1.0f));
}

inline Vec3 reflect(const Vec3& w, const Vec3& n) { return -w + 2.0f * glm::dot(w, n) * n; }

}  // namespace kozu
