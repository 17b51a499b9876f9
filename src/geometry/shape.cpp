#include "geometry/shape.h"

#include "core/warp.h"

#include <stdexcept>

namespace kozu {

TriangleMesh::TriangleMesh(std::vector<Vec3> positions, std::vector<uint32_t> indices, std::vector<Vec3> normals,
                           std::vector<Vec2> uvs)
    : vertex_count_(positions.size()),
      positions_(std::move(positions)),
      indices_(std::move(indices)),
      normals_(std::move(normals)),
      uvs_(std::move(uvs)) {
  positions_.push_back(Vec3(0.0f));  // padding read by Embree's SIMD loads
  for (Vec3& n : normals_) {
    const float l = glm::length(n);
    n = l > 0.0f ? n / l : Vec3(0.0f);
  }
}

unsigned TriangleMesh::attach(RTCDevice device, RTCScene scene) const {
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, positions_.data(), 0, sizeof(Vec3),
                             vertex_count_);
  rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, indices_.data(), 0, 3 * sizeof(uint32_t),
                             primitive_count());
  rtcCommitGeometry(geom);
  const unsigned id = rtcAttachGeometry(scene, geom);
  rtcReleaseGeometry(geom);
  return id;
}

void TriangleMesh::interaction(const Ray& ray, float t, uint32_t prim, float u, float v, const Vec3& ng,
                               SurfaceInteraction& si) const {
  const uint32_t i0 = indices_[3 * prim], i1 = indices_[3 * prim + 1], i2 = indices_[3 * prim + 2];
  const Vec3 &p0 = positions_[i0], &p1 = positions_[i1], &p2 = positions_[i2];
  const float w = 1.0f - u - v;
  si.p = w * p0 + u * p1 + v * p2;
  si.ng = glm::normalize(ng);
  si.t = t;
  si.wo = -ray.d;
  si.front_face = glm::dot(si.wo, si.ng) > 0.0f;
  Vec3 ns = si.ng;
  if (!normals_.empty()) {
    const Vec3 n = w * normals_[i0] + u * normals_[i1] + v * normals_[i2];
    const float l = glm::length(n);
    if (l > 0.0f) {
      ns = n / l;
      // Keep the shading normal on the geometric front side.
      if (glm::dot(ns, si.ng) < 0.0f) ns = -ns;
    }
  }
  si.uv = uvs_.empty() ? Vec2(u, v) : w * uvs_[i0] + u * uvs_[i1] + v * uvs_[i2];
  si.shading = Frame(ns);
  si.shape = this;
  si.prim = prim;
}

float TriangleMesh::primitive_area(uint32_t prim) const {
  const Vec3 a = triangle_vertex(prim, 0), b = triangle_vertex(prim, 1), c = triangle_vertex(prim, 2);
  return 0.5f * glm::length(glm::cross(b - a, c - a));
}

void TriangleMesh::bounds(Vec3& lo, Vec3& hi) const {
  for (size_t i = 0; i < vertex_count_; ++i) {
    lo = glm::min(lo, positions_[i]);
    hi = glm::max(hi, positions_[i]);
  }
}

unsigned Sphere::attach(RTCDevice device, RTCScene scene) const {
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
  auto* buf = static_cast<float*>(
      rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), 1));
  buf[0] = center_.x;
  buf[1] = center_.y;
  buf[2] = center_.z;
  buf[3] = radius_;
  rtcCommitGeometry(geom);
  const unsigned id = rtcAttachGeometry(scene, geom);
  rtcReleaseGeometry(geom);
  return id;
}

void Sphere::interaction(const Ray& ray, float t, uint32_t prim, float, float, const Vec3&,
                         SurfaceInteraction& si) const {
  const Vec3 hit = ray.at(t);
  Vec3 n = hit - center_;
  const float l = glm::length(n);
  n = l > 0.0f ? n / l : Vec3(0, 0, 1);
  // At grazing incidence t is ill-conditioned and the normal from o + t d can face the wrong way,
  // which would send a two-sided BSDF into the sphere. Which root was hit is known exactly: the near
  // root (before the chord's midpoint) enters (d . n < 0), the far one leaves (d . n > 0). Enforce that
  // sign. (The far root of a ray from outside is hit by queries that start past the near one.) Near
  // tangency the roots merge and t's rounding decides nothing: there, a ray from outside enters.
  const bool from_outside = length_sq(ray.o - center_) > radius_ * radius_;
  const float t_mid = glm::dot(center_ - ray.o, ray.d) / glm::dot(ray.d, ray.d);
  const bool entering = from_outside && t < t_mid + 1e-2f * radius_;
  const float dn = glm::dot(ray.d, n);
  constexpr float kMinCos = 1e-5f;
  if (entering ? dn > -kMinCos : dn < kMinCos) {
    n = glm::normalize(n - (dn + (entering ? kMinCos : -kMinCos)) * ray.d);
  }
  // Re-project onto the surface: removes the error of o + t d along the normal.
  si.p = center_ + radius_ * n;
  si.p_error = position_error();
  si.ng = n;
  si.t = t;
  si.wo = -ray.d;
  si.front_face = glm::dot(si.wo, n) > 0.0f;
  const float phi = std::atan2(n.z, n.x);
  // Latitude-longitude: v = 1 at the +y pole, so an image's top row (textures/image_texture.h) lies there.
  si.uv = Vec2((phi < 0 ? phi + kTwoPi : phi) * kInv2Pi, 1.0f - safe_acos(n.y) * kInvPi);
  si.shading = Frame(n);
  si.shape = this;
  si.prim = prim;
}

AreaSample Sphere::sample_surface(const Vec2& u) const {
  const Vec3 n = warp::square_to_uniform_sphere(u);
  AreaSample s;
  s.p = center_ + radius_ * n;
  s.n = n;
  s.pdf_area = 1.0f / primitive_area(0);
  return s;
}

void Sphere::bounds(Vec3& lo, Vec3& hi) const {
  lo = glm::min(lo, center_ - Vec3(radius_));
  hi = glm::max(hi, center_ + Vec3(radius_));
}

}  // namespace kozu
