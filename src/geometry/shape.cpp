#include "geometry/shape.h"

#include "core/transform.h"
#include "core/warp.h"
#include "geometry/mesh_tangents.h"

#include <stdexcept>
#include <unordered_map>

namespace kozu {

TriangleMesh::TriangleMesh(std::vector<Vec3> positions, std::vector<uint32_t> indices, std::vector<Vec3> normals,
                           std::vector<Vec2> uvs, std::vector<Vec4> tangents)
    : vertex_count_(positions.size()),
      positions_(std::move(positions)),
      indices_(std::move(indices)),
      normals_(std::move(normals)),
      uvs_(std::move(uvs)),
      tangents_(std::move(tangents)) {
  positions_.push_back(Vec3(0.0f));  // padding read by Embree's SIMD loads
  for (Vec3& n : normals_) {
    const float l = glm::length(n);
    n = l > 0.0f ? n / l : Vec3(0.0f);
  }
  for (Vec4& t : tangents_) t.w = t.w < 0.0f ? -1.0f : 1.0f;
}

void TriangleMesh::set_groups(std::vector<uint32_t> groups, std::vector<std::string> names) {
  groups_ = std::move(groups);
  group_names_ = std::move(names);
}

std::vector<std::pair<uint32_t, std::unique_ptr<TriangleMesh>>> TriangleMesh::split_by_group() const {
  std::vector<std::pair<uint32_t, std::unique_ptr<TriangleMesh>>> out;
  for (uint32_t g = 0; g < group_names_.size(); ++g) {
    std::vector<uint32_t> remap(vertex_count_, UINT32_MAX);
    std::vector<Vec3> p, n;
    std::vector<Vec2> uv;
    std::vector<Vec4> t;
    std::vector<uint32_t> idx;
    for (size_t tri = 0; tri < groups_.size(); ++tri) {
      if (groups_[tri] != g) continue;
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = indices_[3 * tri + k];
        if (remap[v] == UINT32_MAX) {
          remap[v] = static_cast<uint32_t>(p.size());
          p.push_back(positions_[v]);
          if (!normals_.empty()) n.push_back(normals_[v]);
          if (!uvs_.empty()) uv.push_back(uvs_[v]);
          if (!tangents_.empty()) t.push_back(tangents_[v]);
        }
        idx.push_back(remap[v]);
      }
    }
    if (!idx.empty())
      out.emplace_back(
          g, std::make_unique<TriangleMesh>(std::move(p), std::move(idx), std::move(n), std::move(uv), std::move(t)));
  }
  return out;
}

void TriangleMesh::prepare_tangents() {
  if (!tangents_.empty() || normals_.empty() || uvs_.empty()) return;
  const std::vector<Vec3> positions(positions_.begin(), positions_.begin() + static_cast<ptrdiff_t>(vertex_count_));
  tangents_ = compute_vertex_tangents(positions, indices_, normals_, uvs_);
}

namespace {
// t without its component along the unit vector n, normalized, with handedness w; zero when nothing is left.
Vec4 tangent_against(const Vec3& t, float w, const Vec3& n) {
  const Vec3 p = t - glm::dot(t, n) * n;
  const float l = glm::length(p);
  if (!(l > 1e-12f) || !std::isfinite(l)) return Vec4(0.0f);
  return Vec4(p / l, w < 0.0f ? -1.0f : 1.0f);
}
}  // namespace

Vec4 TriangleMesh::tangent(const SurfaceInteraction& si) const {
  const Vec3& n = si.shading.n;
  if (!tangents_.empty()) {
    const uint32_t i0 = indices_[3 * si.prim], i1 = indices_[3 * si.prim + 1], i2 = indices_[3 * si.prim + 2];
    // si.uv is not the barycentric pair when the mesh has texture coordinates: recover the barycentrics from p.
    const Vec3 &p0 = positions_[i0], &p1 = positions_[i1], &p2 = positions_[i2];
    const Vec3 e1 = p1 - p0, e2 = p2 - p0, d = si.p - p0;
    const float d11 = glm::dot(e1, e1), d12 = glm::dot(e1, e2), d22 = glm::dot(e2, e2);
    const float det = d11 * d22 - d12 * d12;
    float b1 = 0.0f, b2 = 0.0f;
    if (det > 0.0f) {
      const float dd1 = glm::dot(d, e1), dd2 = glm::dot(d, e2);
      b1 = (d22 * dd1 - d12 * dd2) / det;
      b2 = (d11 * dd2 - d12 * dd1) / det;
    }
    const float b0 = 1.0f - b1 - b2;
    const Vec4 t = b0 * tangents_[i0] + b1 * tangents_[i1] + b2 * tangents_[i2];
    return tangent_against(Vec3(t), t.w, n);
  }
  // Flat triangles: the triangle's own dp/du; the handedness from its dp/dv.
  Vec3 dpdu, dpdv;
  uv_derivatives(si, &dpdu, &dpdv);
  return tangent_against(dpdu, glm::dot(glm::cross(n, dpdu), dpdv), n);
}

Vec2 TriangleMesh::hit_uv(const Ray&, float, uint32_t prim, float u, float v) const {
  if (uvs_.empty()) return Vec2(u, v);
  const uint32_t i0 = indices_[3 * prim], i1 = indices_[3 * prim + 1], i2 = indices_[3 * prim + 2];
  return (1.0f - u - v) * uvs_[i0] + u * uvs_[i1] + v * uvs_[i2];
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

struct TriangleMesh::Rest {
  std::vector<Vec3> positions, normals;
  std::vector<Vec4> tangents;
};

void TriangleMesh::set_pose(const Mat4& pose) {
  if (!rest_) rest_ = std::make_shared<const Rest>(Rest{positions_, normals_, tangents_});
  const Transform t(pose);
  for (size_t i = 0; i < vertex_count_; ++i) positions_[i] = t.point(rest_->positions[i]);
  for (size_t i = 0; i < normals_.size(); ++i) {
    const Vec3 n = t.normal(rest_->normals[i]);
    const float l = glm::length(n);
    normals_[i] = l > 0.0f ? n / l : n;
  }
  // Tangents computed after the first pose (prepare_tangents) are in the posed frame already: they are
  // recomputed from the rest tangents only when those exist.
  for (size_t i = 0; i < tangents_.size() && i < rest_->tangents.size(); ++i) {
    const Vec3 v = t.vector(Vec3(rest_->tangents[i]));
    const float l = glm::length(v);
    tangents_[i] = Vec4(l > 0.0f ? v / l : v, rest_->tangents[i].w);
  }
}

void TriangleMesh::refresh(RTCGeometry geom) const {
  rtcUpdateGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0);
  rtcCommitGeometry(geom);
}

void TriangleMesh::interaction(const Ray& ray, float t, uint32_t prim, float u, float v, const Vec3& ng,
                               SurfaceInteraction& si) const {
  const uint32_t i0 = indices_[3 * prim], i1 = indices_[3 * prim + 1], i2 = indices_[3 * prim + 2];
  const Vec3 &p0 = positions_[i0], &p1 = positions_[i1], &p2 = positions_[i2];
  const float w = 1.0f - u - v;
  si.p = w * p0 + u * p1 + v * p2;
  // Embree's ng is the edges' cross product, whose squared length overflows float for triangles wider than about
  // 4e9 (a valid 2e10 polygon): scaled by its largest component first, it normalizes at any size.
  const Vec3 g = ng * (1.0f / max_component(glm::abs(ng)));  // one division, not three: this runs at every hit
  si.ng = g * (1.0f / std::sqrt(glm::dot(g, g)));
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

void TriangleMesh::uv_derivatives(const SurfaceInteraction& si, Vec3* dpdu, Vec3* dpdv) const {
  const uint32_t i0 = indices_[3 * si.prim], i1 = indices_[3 * si.prim + 1], i2 = indices_[3 * si.prim + 2];
  // Without texture coordinates (u, v) are the barycentrics of corners 1 and 2 (TriangleMesh::interaction).
  const Vec2 uv0 = uvs_.empty() ? Vec2(0, 0) : uvs_[i0], uv1 = uvs_.empty() ? Vec2(1, 0) : uvs_[i1],
             uv2 = uvs_.empty() ? Vec2(0, 1) : uvs_[i2];
  triangle_uv_derivatives(positions_[i0], positions_[i1], positions_[i2], uv0, uv1, uv2, dpdu, dpdv);
}

float TriangleMesh::curvature(const SurfaceInteraction& si) const {
  if (normals_.empty()) return 0.0f;
  const uint32_t* idx = &indices_[3 * si.prim];
  Vec3 n_sum(0.0f);
  float k = 0.0f;
  for (int e = 0; e < 3; ++e) {
    const uint32_t i = idx[e], j = idx[(e + 1) % 3];
    const Vec3 dp = positions_[i] - positions_[j];
    const float l2 = glm::dot(dp, dp);
    if (l2 > 0.0f) k += glm::dot(normals_[i] - normals_[j], dp) / l2;
    n_sum += normals_[i];
  }
  // Vertex normals on ng's back side (TriangleMesh::interaction flips the shading normal): the curvature flips too.
  return (glm::dot(n_sum, si.ng) < 0.0f ? -k : k) / 3.0f;
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

void Sphere::set_pose(const Mat4& pose) {
  if (!rest_) rest_ = std::make_pair(center_, radius_);
  const Mat3 m(pose);
  center_ = Transform(pose).point(rest_->first);
  radius_ = rest_->second * (glm::length(m[0]) + glm::length(m[1]) + glm::length(m[2])) / 3.0f;
}

void Sphere::refresh(RTCGeometry geom) const {
  auto* buf = static_cast<float*>(rtcGetGeometryBufferData(geom, RTC_BUFFER_TYPE_VERTEX, 0));
  buf[0] = center_.x;
  buf[1] = center_.y;
  buf[2] = center_.z;
  buf[3] = radius_;
  rtcUpdateGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0);
  rtcCommitGeometry(geom);
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

namespace {
// A sphere's (u, v) at the point along n from its centre (any length; cos_theta its polar cosine): latitude-longitude,
// φ from +x towards −z, so that u runs left to right seen from outside (y up) and an image reads unmirrored; v = 1 at
// the +y pole, so its top row (textures/image_texture.h) lies there. One mapping for the hit and for hit_uv's any-hit
// lookups; fast_atan2 and fast_acos (core/math.h), since every hit pays for its uv, used or not.
Vec2 sphere_uv(const Vec3& n, float cos_theta) {
  const float phi = fast_atan2(-n.z, n.x);
  return Vec2((phi < 0 ? phi + kTwoPi : phi) * kInv2Pi, 1.0f - fast_acos(cos_theta) * kInvPi);
}
}  // namespace

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
  si.uv = sphere_uv(n, n.y);
  si.shading = Frame(n);
  si.shape = this;
  si.prim = prim;
}

void Sphere::uv_derivatives(const SurfaceInteraction& si, Vec3* dpdu, Vec3* dpdv) const {
  // p = c + r (sin t cos f, cos t, −sin t sin f) with u = f / 2 pi and v = 1 − t / pi (Sphere::interaction).
  const Vec3 n = (si.p - center_) / radius_;
  const float s = std::sqrt(n.x * n.x + n.z * n.z);  // sin t
  if (!(s > 1e-6f)) {
    *dpdu = *dpdv = Vec3(0.0f);
    return;
  }
  *dpdu = kTwoPi * radius_ * Vec3(n.z, 0.0f, -n.x);
  *dpdv = -kPi * radius_ * Vec3(n.y * n.x / s, -s, n.y * n.z / s);
}

Vec4 Sphere::tangent(const SurfaceInteraction& si) const {
  const Vec3 n = (si.p - center_) / radius_;
  const Vec3 t(n.z, 0.0f, -n.x);  // dp/du's direction (Sphere::uv_derivatives)
  const Vec3& ns = si.shading.n;
  const Vec3 p = t - glm::dot(t, ns) * ns;
  const float l = glm::length(p);
  if (!(l > 1e-6f)) return Vec4(0.0f);
  return Vec4(p / l, 1.0f);  // dp/dv = cross(n, dp/du) · |dp/dv| / |dp/du|: right-handed
}

Vec2 Sphere::hit_uv(const Ray& ray, float t, uint32_t, float, float) const {
  const Vec3 n = ray.at(t) - center_;
  const float l = glm::length(n);
  return sphere_uv(n, l > 0.0f ? n.y / l : 1.0f);
}

void uv_footprint(const SurfaceInteraction& si, Vec2* duvdx, Vec2* duvdy) {
  *duvdx = *duvdy = Vec2(0.0f);
  if (!(si.cone_width > 0.0f) || !si.shape) return;
  Vec3 dpdu, dpdv;
  surface_uv_derivatives(si, &dpdu, &dpdv);
  const float a00 = glm::dot(dpdu, dpdu), a01 = glm::dot(dpdu, dpdv), a11 = glm::dot(dpdv, dpdv);
  const float det = a00 * a11 - a01 * a01;
  if (!(det > 1e-30f) || !std::isfinite(det)) return;
  const Vec3& n = si.ng;
  const float cos_t = std::max(std::abs(glm::dot(si.wo, n)), 1e-3f);  // grazing: a long but finite footprint
  Vec3 h1 = -si.wo - glm::dot(-si.wo, n) * n;
  const float l = glm::length(h1);
  h1 = l > 1e-6f ? h1 / l : Frame(n).s;
  const Vec3 h2 = glm::cross(n, h1);
  // (du, dv) = A^-1 (dp/du . a, dp/dv . a), A the Gram matrix of dp/du, dp/dv.
  const auto to_uv = [&](const Vec3& a) {
    const float b0 = glm::dot(dpdu, a), b1 = glm::dot(dpdv, a);
    return Vec2(a11 * b0 - a01 * b1, a00 * b1 - a01 * b0) / det;
  };
  *duvdx = to_uv(h1 * (si.cone_width / cos_t));
  *duvdy = to_uv(h2 * si.cone_width);
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

size_t TriangleMesh::open_edges() const {
  // Vertices closer than 10⁻⁶ of the mesh's extent are one: a UV or normal seam splits vertices, not the surface,
  // and a seam computed twice (cos 0 and cos 2π) differs in the last bits. A hash grid of that cell size, each
  // vertex compared with the 27 cells around its own.
  Vec3 lo(kInfinity), hi(-kInfinity);
  for (uint32_t i = 0; i < vertex_count_; ++i) lo = glm::min(lo, positions_[i]), hi = glm::max(hi, positions_[i]);
  const float eps = std::max(1e-6f * glm::length(hi - lo), 1e-30f);
  const auto cell_key = [](int64_t x, int64_t y, int64_t z) {
    return uint64_t(x) * 0x9e3779b97f4a7c15ull ^ uint64_t(y) * 0xc2b2ae3d27d4eb4full ^
           uint64_t(z) * 0x165667b19e3779f9ull;
  };
  std::unordered_map<uint64_t, std::vector<uint32_t>> cells;
  std::vector<uint32_t> canonical(vertex_count_);
  for (uint32_t i = 0; i < vertex_count_; ++i) {
    const Vec3 q = glm::floor((positions_[i] - lo) / eps);
    const auto cx = static_cast<int64_t>(q.x), cy = static_cast<int64_t>(q.y), cz = static_cast<int64_t>(q.z);
    canonical[i] = i;
    for (int64_t dx = -1; dx <= 1 && canonical[i] == i; ++dx)
      for (int64_t dy = -1; dy <= 1 && canonical[i] == i; ++dy)
        for (int64_t dz = -1; dz <= 1 && canonical[i] == i; ++dz)
          if (const auto it = cells.find(cell_key(cx + dx, cy + dy, cz + dz)); it != cells.end())
            for (uint32_t j : it->second)
              if (glm::length(positions_[j] - positions_[i]) <= eps) {
                canonical[i] = j;
                break;
              }
    if (canonical[i] == i) cells[cell_key(cx, cy, cz)].push_back(i);
  }
  // Each undirected edge's triangle count: an edge of a closed surface has an even one (2, or 4 where sheets meet).
  std::unordered_map<uint64_t, uint32_t> edges;
  edges.reserve(indices_.size());
  for (size_t t = 0; t + 2 < indices_.size(); t += 3)
    for (int k = 0; k < 3; ++k) {
      uint32_t a = canonical[indices_[t + k]], b = canonical[indices_[t + (k + 1) % 3]];
      if (a > b) std::swap(a, b);
      ++edges[(uint64_t(a) << 32) | b];
    }
  size_t open = 0;
  for (const auto& [edge, count] : edges) open += count % 2;
  return open;
}

}  // namespace kozu
