#include "lights/ltc_polygon_sampler.h"

#include <algorithm>
#include <cmath>

namespace kozu {

namespace {

// Van Oosterom & Strackee 1983: the solid angle of the spherical triangle of unit a, b, c.
double triangle_solid_angle(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const double num = std::abs(glm::dot(a, glm::cross(b, c)));
  const double den = 1.0 + glm::dot(a, b) + glm::dot(b, c) + glm::dot(c, a);
  return 2.0 * std::atan2(num, den);
}

// The unit component of v orthogonal to the unit n (v and n not parallel).
Vec3d orthogonal(const Vec3d& v, const Vec3d& n) {
  const Vec3d w = v - glm::dot(v, n) * n;
  const double len = glm::length(w);
  return len > 0.0 ? w / len : Vec3d(0.0);
}

// The angle at a between the great arcs a→b and a→c.
double corner_angle(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d tb = orthogonal(b, a), tc = orthogonal(c, a);
  return std::atan2(glm::length(glm::cross(tb, tc)), glm::dot(tb, tc));
}

}  // namespace

LtcPolygonSampler::LtcPolygonSampler(const Ltc& ltc, std::span<const std::array<Vec3, 3>> triangles) : ltc_(&ltc) {
  const glm::dmat3 m_inv(ltc.m_inv());
  for (size_t t = 0; t < std::min(triangles.size(), size_t(kMaxTriangles)); ++t) {
    // Into the cosine configuration, then clipped to z >= 0 (Sutherland–Hodgman: at most four corners).
    std::array<Vec3d, 4> c;
    int m = 0;
    for (int i = 0; i < 3; ++i) {
      const Vec3d a = m_inv * Vec3d(triangles[t][i]), b = m_inv * Vec3d(triangles[t][(i + 1) % 3]);
      const bool a_in = a.z >= 0.0, b_in = b.z >= 0.0;
      if (a_in) c[m++] = a;
      if (a_in != b_in) c[m++] = a + (b - a) * (a.z / (a.z - b.z));
    }
    bool degenerate = m < 3;
    for (int i = 0; i < m && !degenerate; ++i) {
      const double len = glm::length(c[i]);
      degenerate = !(len > 0.0);  // a corner at the shading point
      if (!degenerate) c[i] /= len;
    }
    if (degenerate) continue;
    for (int i = 1; i + 1 < m; ++i) {
      const double omega = triangle_solid_angle(c[0], c[i], c[i + 1]);
      if (!(omega > 0.0)) continue;
      tri_[n_++] = Spherical{c[0], c[i], c[i + 1], omega};
      solid_angle_ += omega;
    }
  }
}

Vec3 LtcPolygonSampler::sample(const Vec2& u) const {
  // The triangle in proportion to its solid angle, u.x reused within it.
  double x = double(u.x) * solid_angle_;
  int k = 0;
  while (k + 1 < n_ && x >= tri_[k].solid_angle) x -= tri_[k++].solid_angle;
  const Spherical& t = tri_[k];
  const double u1 = std::clamp(x / t.solid_angle, 0.0, 1.0), u2 = u.y;
  // Arvo 1995: the sub-triangle A B C' of area u1 Ω (C' on the arc A C), then a point on the arc B C'.
  const double alpha = corner_angle(t.a, t.b, t.c);
  const double area = u1 * t.solid_angle;
  const double s = std::sin(area - alpha), c = std::cos(area - alpha);
  const double cos_alpha = std::cos(alpha), sin_alpha = std::sin(alpha);
  const double uu = c - cos_alpha, vv = s + sin_alpha * glm::dot(t.a, t.b);
  const double den = (vv * s + uu * c) * sin_alpha;
  const double q = den != 0.0 ? std::clamp(((vv * c - uu * s) * cos_alpha - vv) / den, -1.0, 1.0) : 1.0;
  const Vec3d c_prime = q * t.a + std::sqrt(std::max(0.0, 1.0 - q * q)) * orthogonal(t.c, t.a);
  const double z = 1.0 - u2 * (1.0 - glm::dot(c_prime, t.b));
  Vec3d p = z * t.b + std::sqrt(std::max(0.0, 1.0 - z * z)) * orthogonal(c_prime, t.b);
  if (!std::isfinite(p.x + p.y + p.z) || !(glm::dot(p, p) > 0.0)) p = t.a;
  return glm::normalize(ltc_->m() * Vec3(p));
}

float LtcPolygonSampler::pdf(const Vec3& w) const {
  if (!(solid_angle_ > 0.0)) return 0.0f;
  const Vec3 wo = ltc_->m_inv() * w;
  if (!(wo.z > 0.0f)) return 0.0f;
  const float len = glm::length(wo);
  return static_cast<float>(ltc_->det_inv() / (double(len) * len * len * solid_angle_));
}

}  // namespace kozu
