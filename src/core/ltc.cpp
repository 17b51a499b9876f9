#include "core/ltc.h"

#include "core/math.h"
#include "core/warp.h"

#include <array>
#include <cmath>

namespace kozu {

Ltc::Ltc(const Mat3& m) : m_(m), m_inv_(glm::inverse(m)), det_inv_(std::abs(glm::determinant(m_inv_))) {}

Ltc Ltc::from_inverse(const Mat3& m_inv) {
  Ltc l;
  l.m_inv_ = m_inv;
  l.m_ = glm::inverse(m_inv);
  l.det_inv_ = std::abs(glm::determinant(m_inv));
  return l;
}

float Ltc::eval(const Vec3& w) const {
  const Vec3 wo = m_inv_ * w;
  if (!(wo.z > 0.0f)) return 0.0f;
  const float l2 = glm::dot(wo, wo);
  // D_o(wo/l) |M⁻¹| / l³ with D_o(x) = x.z/π: wo.z |M⁻¹| / (π l⁴).
  return wo.z * det_inv_ * kInvPi / (l2 * l2);
}

Vec3 Ltc::sample(const Vec2& u) const { return glm::normalize(m_ * warp::square_to_cosine_hemisphere(u)); }

float Ltc::integrate_polygon(std::span<const Vec3> vertices) const {
  std::array<Vec3, kMaxVertices> p;
  const size_t n = std::min(vertices.size(), p.size());
  for (size_t i = 0; i < n; ++i) p[i] = m_inv_ * vertices[i];
  return static_cast<float>(clamped_cosine_polygon_integral(std::span<const Vec3>(p.data(), n)));
}

namespace {

// Eq. (11)'s term of the edge from a to b (not necessarily unit), in double: for the short edges, whose cross product
// float has too few digits for.
double edge_term_double(const Vec3d& a_in, const Vec3d& b_in) {
  const Vec3d a = glm::normalize(a_in), b = glm::normalize(b_in);
  const Vec3d x = glm::cross(a, b);
  const double s = glm::length(x);
  return s > 0.0 ? double(fast_atan2(float(s), float(glm::dot(a, b)))) / s * x.z : 0.0;
}

// The unclipped polygon (every point at z >= 0, none at the origin), in float but for its short edges: the cross
// product of two unit vectors carries an absolute error of a few 10⁻⁸ per component, so an edge of sine s may keep
// a relative error of about 10⁻⁷ / s where the components cancel; below kShortEdge the edge is taken in double
// (edge_term_double), a margin (Ltc.SmallDistantPolygonsNeedDouble's squares keep 10⁻⁷ in float too, their
// components not cancelling). Over 2·10⁶ random quads above the horizon the worst absolute error against std::atan2
// in double is 1.0·10⁻⁷, as the double form's with fast_atan2; a quad 141 → 96 ns (bench_ltc).
double polygon_integral_above(std::span<const Vec3> p) {
  constexpr float kShortEdge = 0.125f;
  double sum = 0.0;
  Vec3 a = glm::normalize(p.back());
  for (size_t i = 0; i < p.size(); ++i) {
    const Vec3 b = glm::normalize(p[i]);
    const Vec3 x = glm::cross(a, b);
    const float s = glm::length(x);
    if (s >= kShortEdge)
      sum += double(fast_atan2(s, glm::dot(a, b)) / s * x.z);
    else
      sum += edge_term_double(Vec3d(p[i == 0 ? p.size() - 1 : i - 1]), Vec3d(p[i]));
    a = b;
  }
  return std::abs(sum) / (2.0 * kPi);
}

}  // namespace

double clamped_cosine_polygon_integral(std::span<const Vec3> p) {
  if (p.size() < 3 || p.size() > size_t(Ltc::kMaxVertices)) return 0.0;
  // Most polygons lie wholly above the horizon (a light in front of the shading point): no clipping, and float.
  bool above = true;
  for (const Vec3& q : p) above = above && q.z >= 0.0f && glm::dot(q, q) > 0.0f;
  if (above) return polygon_integral_above(p);
  // Clip to z >= 0 (Sutherland–Hodgman against one plane through the origin: a point of a straight edge projects
  // onto the great arc of that edge, so clipping the segments clips the spherical polygon). A convex polygon
  // keeps at most n + 1 points; a concave one (a `polygon` shape may be) crosses the plane k <= n times and keeps
  // at most n + k/2.
  std::array<Vec3d, 2 * Ltc::kMaxVertices> c;
  size_t m = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    const Vec3d a(p[i]), b(p[(i + 1) % p.size()]);
    const bool a_in = a.z >= 0.0, b_in = b.z >= 0.0;
    if (a_in) c[m++] = a;
    if (a_in != b_in) c[m++] = a + (b - a) * (a.z / (a.z - b.z));
  }
  if (m < 3) return 0.0;
  for (size_t i = 0; i < m; ++i)
    if (!(glm::dot(c[i], c[i]) > 0.0)) return 0.0;  // a corner at the shading point: no solid angle to speak of
  // Eq. (11), each edge's term θ (p_i × p_j)_z / ‖p_i × p_j‖ with θ = atan2(‖p_i × p_j‖, ⟨p_i, p_j⟩): exact for
  // short edges, where acos of the dot product has no digits left. fast_atan2 (core/math.h), a float polynomial
  // within a few ulps of θ at any angle, short edges included: std::atan2 in double was most of "ltc"'s closed form
  // (docs/lights.md), and the float result keeps no more digits.
  double sum = 0.0;
  Vec3d a = glm::normalize(c[m - 1]);
  for (size_t i = 0; i < m; ++i) {
    const Vec3d b = glm::normalize(c[i]);
    const Vec3d x = glm::cross(a, b);
    const double s = glm::length(x);
    if (s > 0.0) sum += double(fast_atan2(float(s), float(glm::dot(a, b)))) / s * x.z;
    a = b;
  }
  return std::abs(sum) / (2.0 * kPi);
}

}  // namespace kozu
