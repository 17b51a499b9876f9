#include "geometry/mesh_tangents.h"

#include "core/frame.h"

namespace kozu {

bool triangle_uv_derivatives(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec2& uv0, const Vec2& uv1,
                             const Vec2& uv2, Vec3* dpdu, Vec3* dpdv) {
  const Vec2 duv02 = uv0 - uv2, duv12 = uv1 - uv2;
  const Vec3 dp02 = p0 - p2, dp12 = p1 - p2;
  const float det = duv02.x * duv12.y - duv02.y * duv12.x;
  if (!(std::abs(det) > 1e-20f)) {
    *dpdu = *dpdv = Vec3(0.0f);
    return false;
  }
  // p − p2 = (u − u2) dp/du + (v − v2) dp/dv at corners 0 and 1, solved for the two derivatives.
  const float inv = 1.0f / det;
  *dpdu = (duv12.y * dp02 - duv02.y * dp12) * inv;
  *dpdv = (duv02.x * dp12 - duv12.x * dp02) * inv;
  return is_finite(*dpdu) && is_finite(*dpdv);
}

namespace {
// v without its component along the unit vector n, normalized; zero when nothing is left.
Vec3 project_normalized(const Vec3& v, const Vec3& n) {
  const Vec3 p = v - glm::dot(v, n) * n;
  const float l = glm::length(p);
  return l > 1e-20f && std::isfinite(l) ? p / l : Vec3(0.0f);
}

float corner_angle(const Vec3& at, const Vec3& a, const Vec3& b) {
  const Vec3 e1 = a - at, e2 = b - at;
  const float l = glm::length(e1) * glm::length(e2);
  return l > 0.0f ? safe_acos(glm::dot(e1, e2) / l) : 0.0f;
}
}  // namespace

std::vector<Vec4> compute_vertex_tangents(const std::vector<Vec3>& positions, const std::vector<uint32_t>& indices,
                                          const std::vector<Vec3>& normals, const std::vector<Vec2>& uvs) {
  const size_t n = positions.size();
  std::vector<Vec3> t_sum(n, Vec3(0.0f)), b_sum(n, Vec3(0.0f));
  for (size_t i = 0; i + 2 < indices.size(); i += 3) {
    const uint32_t v[3] = {indices[i], indices[i + 1], indices[i + 2]};
    Vec3 dpdu, dpdv;
    if (!triangle_uv_derivatives(positions[v[0]], positions[v[1]], positions[v[2]], uvs[v[0]], uvs[v[1]], uvs[v[2]],
                                 &dpdu, &dpdv))
      continue;
    for (int k = 0; k < 3; ++k) {
      const Vec3& nv = normals[v[k]];
      const float angle = corner_angle(positions[v[k]], positions[v[(k + 1) % 3]], positions[v[(k + 2) % 3]]);
      t_sum[v[k]] += angle * project_normalized(dpdu, nv);
      b_sum[v[k]] += angle * project_normalized(dpdv, nv);
    }
  }
  std::vector<Vec4> tangents(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec3& nv = normals[i];
    Vec3 t = project_normalized(t_sum[i], nv);
    if (t == Vec3(0.0f)) {
      tangents[i] = Vec4(Frame(glm::dot(nv, nv) > 0.0f ? nv : Vec3(0, 0, 1)).s, 1.0f);
      continue;
    }
    const float w = glm::dot(glm::cross(nv, t), b_sum[i]) < 0.0f ? -1.0f : 1.0f;
    tangents[i] = Vec4(t, w);
  }
  return tangents;
}

}  // namespace kozu
