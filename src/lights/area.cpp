#include "lights/area.h"

#include "core/ltc.h"
#include "core/warp.h"

namespace kozu {

namespace {

// Radiance of a one- or two-sided emitter seen at cosine c = dot(n, w), w pointing away from it.
inline Rgb emitted(const Rgb& radiance, bool two_sided, float c) {
  return (c > 0.0f || (two_sided && c < 0.0f)) ? radiance : Rgb(0.0f);
}
inline Rgb emitted(const Rgb& radiance, bool two_sided, const Vec3& n, const Vec3& w) {
  return emitted(radiance, two_sided, glm::dot(n, w));
}

// Completes a light sample from a point chosen on the light by area: the solid-angle density is
// pdf_area * dist^2 / |cos theta_light|.
LightSample from_area_sample(const LightSampleContext& ctx, const AreaSample& as, float pdf_area, const Rgb& radiance,
                             bool two_sided) {
  LightSample ls;
  const Vec3 d = as.p - ctx.p;
  const float dist2 = glm::dot(d, d);
  const float inv_dist = 1.0f / std::sqrt(dist2);
  ls.wi = d * inv_dist;
  const float cos_l = glm::dot(as.n, ls.wi);
  const float pdf = pdf_area * dist2 / std::abs(cos_l);  // dw = |cos theta_l| dA / r^2
  if (!(pdf > 0.0f) || !std::isfinite(pdf)) return ls;   // also rejects dist2 == 0 and grazing points
  ls.pdf = pdf;
  ls.radiance = emitted(radiance, two_sided, -cos_l);
  ls.p = as.p;
  ls.n = as.n;
  return ls;
}

}  // namespace

Rgb DiffuseAreaLight::eval(const LightHit& hit) const {
  return hit.si ? emitted(radiance_, two_sided_, hit.si->ng, hit.si->wo) : Rgb(0.0f);
}

EmitterTriangle::EmitterTriangle(const Vec3& a, const Vec3& b, const Vec3& c) : p0(a), e1(b - a), e2(c - a) {
  const Vec3 cr = glm::cross(e1, e2);
  const float len = glm::length(cr);
  n = cr / len;
  area = 0.5f * len;
}

AreaSample EmitterTriangle::sample(const Vec2& u) const {
  // Barycentrics (b0, b1) weight the corners p0 and p0 + e1.
  const Vec2 b = warp::square_to_uniform_triangle(u);  // Heitz 2019, the low-distortion square-to-triangle map
  AreaSample s;
  s.p = p0 + b.y * e1 + (1.0f - b.x - b.y) * e2;
  s.n = n;
  s.pdf_area = 1.0f / area;
  return s;
}

TriangleLight::TriangleLight(const TriangleMesh* mesh, uint32_t prim, const Rgb& radiance, bool two_sided)
    : DiffuseAreaLight(radiance, two_sided), mesh_(mesh), prim_(prim) {
  refit();
}

void TriangleLight::refit() {
  tri_ = EmitterTriangle(mesh_->triangle_vertex(prim_, 0), mesh_->triangle_vertex(prim_, 1),
                         mesh_->triangle_vertex(prim_, 2));
}

LightSample TriangleLight::sample(const LightSampleContext& ctx, const Vec2& u) const {
  const AreaSample as = tri_.sample(u);
  return from_area_sample(ctx, as, as.pdf_area, radiance_, two_sided_);
}

// area.h: Phi = pi A L per emitting side (Lambertian emission integrated over the hemisphere).
Rgb TriangleLight::power() const { return radiance_ * (kPi * tri_.area * (two_sided_ ? 2.0f : 1.0f)); }

// A flat emitter: its normals one axis (both ways when two-sided), each emitting over a hemisphere; intensity A L.
static LightBounds flat_bounds(std::span<const Vec3> points, const Vec3& n, bool two_sided, float intensity) {
  LightBounds b;
  b.lo = b.hi = points[0];
  for (const Vec3& p : points) {
    b.lo = glm::min(b.lo, p);
    b.hi = glm::max(b.hi, p);
  }
  b.cone = DirectionCone{n, two_sided ? kPi : 0.0f, 0.5f * kPi};
  b.phi = intensity;
  return b;
}

LightBounds TriangleLight::bounds() const {
  const Vec3 p[3] = {tri_.p0, tri_.p0 + tri_.e1, tri_.p0 + tri_.e2};
  return flat_bounds(p, tri_.n, two_sided_, average(radiance_) * tri_.area);
}

float TriangleLight::pdf(const LightSampleContext& ctx, const LightHit& hit) const {
  return hit.si ? area_to_solid_angle(1.0f / tri_.area, ctx.p, hit.si->p, hit.si->ng) : 0.0f;
}

namespace {

// The barycentrics (b1, b2) along tri.e1 and tri.e2 of the point x of its plane; false for a degenerate triangle.
bool barycentrics(const EmitterTriangle& tri, const Vec3& x, float* b1, float* b2) {
  const Vec3 q = x - tri.p0;
  const float d11 = glm::dot(tri.e1, tri.e1), d12 = glm::dot(tri.e1, tri.e2), d22 = glm::dot(tri.e2, tri.e2);
  const float q1 = glm::dot(q, tri.e1), q2 = glm::dot(q, tri.e2);
  const float den = d11 * d22 - d12 * d12;
  if (!(den > 0.0f)) return false;
  *b1 = (d22 * q1 - d12 * q2) / den;
  *b2 = (d11 * q2 - d12 * q1) / den;
  return true;
}

bool inside(float b1, float b2) { return b1 >= 0.0f && b2 >= 0.0f && b1 + b2 <= 1.0f; }

// Where the ray from o along the unit d meets the plane of tri (t > 0), if it does.
bool plane_hit(const EmitterTriangle& tri, const Vec3& o, const Vec3& d, Vec3* x) {
  const float dn = glm::dot(d, tri.n);
  if (dn == 0.0f) return false;
  const float t = glm::dot(tri.p0 - o, tri.n) / dn;
  if (!(t > 0.0f) || !std::isfinite(t)) return false;
  *x = o + t * d;
  return true;
}

}  // namespace

bool TriangleLight::along(const LightSampleContext& ctx, const Vec3& wi, LightSample* ls) const {
  Vec3 x;
  float b1, b2;
  if (!plane_hit(tri_, ctx.p, wi, &x) || !barycentrics(tri_, x, &b1, &b2) || !inside(b1, b2)) return false;
  *ls = from_area_sample(ctx, AreaSample{x, tri_.n, 1.0f / tri_.area}, 1.0f / tri_.area, radiance_, two_sided_);
  return ls->valid();
}

PolygonLight::PolygonLight(const TriangleMesh* mesh, const Rgb& radiance, bool two_sided,
                           std::unique_ptr<const Texture> texture)
    : DiffuseAreaLight(radiance, two_sided), mesh_(mesh), area_(0), texture_(std::move(texture)) {
  fit();
  if (texture_) prepare_texture();
}

void PolygonLight::fit() {
  const TriangleMesh* mesh = mesh_;
  triangles_.clear();
  triangle_uvs_.clear();
  corners_.clear();
  centre_ = Vec3(0.0f);
  area_ = 0.0f;
  parallelogram_ = false;
  std::vector<float> areas(mesh->primitive_count());
  for (uint32_t i = 0; i < areas.size(); ++i) {
    triangles_.emplace_back(mesh->triangle_vertex(i, 0), mesh->triangle_vertex(i, 1), mesh->triangle_vertex(i, 2));
    triangle_uvs_.push_back({mesh->triangle_uv(i, 0), mesh->triangle_uv(i, 1), mesh->triangle_uv(i, 2)});
    areas[i] = triangles_.back().area;
    area_ += areas[i];
  }
  pick_ = AliasTable(areas);
  for (uint32_t i = 0; i < mesh->vertex_count(); ++i) corners_.push_back(mesh->position(i));
  for (const Vec3& c : corners_) centre_ += c / static_cast<float>(corners_.size());
  // A quad v0 v1 v2 v3 is a parallelogram when v0 + v2 = v1 + v3 (up to rounding).
  if (mesh->vertex_count() == 4) {
    const Vec3 v0 = mesh->position(0), v1 = mesh->position(1), v2 = mesh->position(2), v3 = mesh->position(3);
    const float size = std::max(glm::length(v1 - v0), glm::length(v3 - v0));
    if (glm::length((v0 + v2) - (v1 + v3)) <= 1e-5f * size) {
      parallelogram_ = true;
      p0_ = v0;
      e1_ = v1 - v0;
      e2_ = v3 - v0;
    }
  }
}

// A pose moves, turns and scales the polygon: its triangles, corners and square anew; a textured light's texel
// grid too (the grid lies in the square, whose shape a non-uniform scale changes).
void PolygonLight::refit() {
  fit();
  if (texture_) prepare_texture();
}

// The texel grid over the square: its mean (power), the sampling distribution and the LTC pyramid.
void PolygonLight::prepare_texture() {
  if (!parallelogram_) {
    // The bounding rectangle in the polygon's plane, along its first edge.
    const Vec3 eu = glm::normalize(corners_[1] - corners_[0]);
    const Vec3 ev = glm::cross(normal(), eu);
    Vec2 lo(kInfinity), hi(-kInfinity);
    for (const Vec3& c : corners_) {
      const Vec2 x(glm::dot(c - corners_[0], eu), glm::dot(c - corners_[0], ev));
      lo = glm::min(lo, x);
      hi = glm::max(hi, x);
    }
    p0_ = corners_[0] + lo.x * eu + lo.y * ev;
    e1_ = (hi.x - lo.x) * eu;
    e2_ = (hi.y - lo.y) * ev;
  }
  constexpr int n = kTexels;
  constexpr float h = 1.0f / float(n);
  std::vector<Rgb> texels(size_t(n) * n);
  Rgb sum(0.0f);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const Vec3 p = p0_ + (float(i) + 0.5f) * h * e1_ + (float(j) + 0.5f) * h * e2_;
      TextureQuery q;
      q.uv = uv_at(p);
      q.duvdx = uv_at(p + h * e1_) - q.uv;  // one texel's footprint
      q.duvdy = uv_at(p + h * e2_) - q.uv;
      texels[size_t(j) * n + size_t(i)] = texture_value(q);
      sum += texels[size_t(j) * n + size_t(i)];
    }
  mean_texture_ = sum / float(n * n);
  if (parallelogram_) {
    // A floor of a tenth of the mean keeps a density wherever a point lookup may differ from its texel's filter.
    const float floor = 0.1f * luminance(mean_texture_);
    std::vector<float> func(texels.size(), 1.0f);
    if (floor > 0.0f)
      for (size_t i = 0; i < texels.size(); ++i) func[i] = std::max(luminance(texels[i]), 0.0f) + floor;
    texel_pick_ = Distribution2D(func, n, n);
  }
  ltc_texture_ = std::make_unique<LtcTexture>(texels, n);
}

Rgb PolygonLight::texture_value(const TextureQuery& q) const {
  Rgb v = texture_->eval(q);
  for (int c = 0; c < 3; ++c) v[c] = std::isfinite(v[c]) && v[c] > 0.0f ? v[c] : 0.0f;
  return v * radiance_;
}

Vec2 PolygonLight::uv_at(const Vec3& p) const {
  // The triangle holding p; outside the polygon, the first triangle's mapping extended (exact for the affine
  // (u, v) of quads and polygons).
  float b1 = 0.0f, b2 = 0.0f;
  size_t t = 0;
  while (t < triangles_.size() && !(barycentrics(triangles_[t], p, &b1, &b2) && inside(b1, b2))) ++t;
  if (t == triangles_.size()) {
    t = 0;
    if (!barycentrics(triangles_[0], p, &b1, &b2)) return triangle_uvs_[0][0];
  }
  const std::array<Vec2, 3>& uv = triangle_uvs_[t];
  return uv[0] + b1 * (uv[1] - uv[0]) + b2 * (uv[2] - uv[0]);
}

Vec2 PolygonLight::square_coordinates(const Vec3& p) const {
  const Vec3 d = p - p0_;
  const float g11 = glm::dot(e1_, e1_), g12 = glm::dot(e1_, e2_), g22 = glm::dot(e2_, e2_);
  const float det = g11 * g22 - g12 * g12;
  const float d1 = glm::dot(d, e1_), d2 = glm::dot(d, e2_);
  return Vec2((g22 * d1 - g12 * d2) / det, (g11 * d2 - g12 * d1) / det);
}

float PolygonLight::area_pdf(const Vec3& p) const {
  if (!texture_ || !parallelogram_) return 1.0f / area_;
  const Vec2 ab = glm::clamp(square_coordinates(p), Vec2(0.0f), Vec2(std::nextafter(1.0f, 0.0f)));
  return texel_pick_.pdf(ab) / area_;
}

Rgb PolygonLight::radiance_at(const Vec3& p) const {
  if (!texture_) return radiance_;
  TextureQuery q;
  q.uv = uv_at(p);
  return texture_value(q);
}

Rgb PolygonLight::eval(const LightHit& hit) const {
  if (!texture_ || !hit.si) return DiffuseAreaLight::eval(hit);
  if (is_black(emitted(Rgb(1.0f), two_sided_, hit.si->ng, hit.si->wo))) return Rgb(0.0f);
  // A point lookup, as for light samples: a footprint-filtered value here (a ray cone after a glossy bounce) would
  // differ from what light sampling sees of the same point, and MIS would average two different emitters.
  TextureQuery q;
  q.uv = hit.si->uv;
  return texture_value(q);
}

Rgb PolygonLight::ltc_radiance(const Ltc& ltc, const Frame& frame, const Vec3& ref) const {
  if (!ltc_texture_) return radiance_;
  return ltc_texture_->fetch(ltc, frame.to_local(p0_ - ref), frame.to_local(e1_), frame.to_local(e2_));
}

LightSample PolygonLight::sample(const LightSampleContext& ctx, const Vec2& u) const {
  return sample(ctx, u, texture_ != nullptr);
}

LightSample PolygonLight::sample(const LightSampleContext& ctx, const Vec2& u, bool by_luminance) const {
  AreaSample as;
  float pdf_area = 1.0f / area_;
  if (parallelogram_) {
    Vec2 ab = u;
    if (by_luminance && texture_) {
      float pdf_ab;
      ab = texel_pick_.sample(u, &pdf_ab);
      pdf_area = pdf_ab / area_;
    }
    as.p = p0_ + ab.x * e1_ + ab.y * e2_;
    as.n = triangles_[0].n;
  } else {
    // u.x picks the triangle; its remapped remainder places the point.
    float ux = u.x;
    const uint32_t tri = triangles_.size() == 1 ? 0 : pick_.sample(u.x, &ux);
    as = triangles_[tri].sample(Vec2(ux, u.y));
  }
  return from_area_sample(ctx, as, pdf_area, radiance_at(as.p), two_sided_);
}

bool PolygonLight::analytic() const { return corners_.size() <= size_t(Ltc::kMaxVertices); }

bool PolygonLight::along(const LightSampleContext& ctx, const Vec3& wi, LightSample* ls) const {
  Vec3 x;
  if (!intersect(ctx.p, wi, &x)) return false;
  *ls = from_area_sample(ctx, AreaSample{x, normal(), area_pdf(x)}, area_pdf(x), radiance_at(x), two_sided_);
  return ls->valid();
}

bool PolygonLight::intersect(const Vec3& o, const Vec3& d, Vec3* p) const {
  const Vec3& n = normal();
  const float dn = glm::dot(d, n);
  if (dn == 0.0f) return false;
  const float t = glm::dot(corners_[0] - o, n) / dn;
  if (!(t > 0.0f)) return false;
  const Vec3 x = o + t * d;
  // Inside one of the triangles (a concave polygon's too).
  for (const EmitterTriangle& tri : triangles_) {
    float b1, b2;
    if (barycentrics(tri, x, &b1, &b2) && inside(b1, b2)) {
      *p = x;
      return true;
    }
  }
  return false;
}

LightBounds PolygonLight::bounds() const {
  return flat_bounds(corners_, normal(), two_sided_, average(texture_ ? mean_texture_ : radiance_) * area_);
}

// A textured light's mean is over its square: for a polygon other than a parallelogram, over its bounding rectangle.
Rgb PolygonLight::power() const {
  return (texture_ ? mean_texture_ : radiance_) * (kPi * area_ * (two_sided_ ? 2.0f : 1.0f));
}

float PolygonLight::pdf(const LightSampleContext& ctx, const LightHit& hit) const {
  return hit.si ? area_to_solid_angle(area_pdf(hit.si->p), ctx.p, hit.si->p, hit.si->ng) : 0.0f;
}

SphereLight::SphereLight(const Sphere* sphere, const Rgb& radiance, bool two_sided)
    : DiffuseAreaLight(radiance, two_sided), sphere_(sphere) {}

LightSample SphereLight::sample(const LightSampleContext& ctx, const Vec2& u) const {
  const Vec3 c = sphere_->center();
  const float r = sphere_->radius();
  const Vec3 to_c = c - ctx.p;
  const float dist2 = glm::dot(to_c, to_c);
  if (dist2 <= r * r * 1.0001f) {
    // Inside (or on) the sphere: sample its surface by area.
    const AreaSample as = sphere_->sample_surface(u);
    LightSample ls = from_area_sample(ctx, as, as.pdf_area, radiance_, two_sided_);
    ls.p_error = sphere_->position_error();
    return ls;
  }
  // Uniform cone of directions subtended by the sphere (pbrt-v4 §6.2.4 style, kept in float).
  const float dist = std::sqrt(dist2);
  const float sin2_max = r * r / dist2;
  const float cos_max = safe_sqrt(1.0f - sin2_max);
  const float one_minus_cos_max = sin2_max / (1.0f + cos_max);  // accurate for small cones
  const float cos_t = 1.0f - u.x * one_minus_cos_max;
  const float sin2_t = std::max(0.0f, 1.0f - cos_t * cos_t);
  // Distance along the ray to the near intersection, from the law of cosines.
  const float t = dist * cos_t - safe_sqrt(r * r - dist2 * sin2_t);
  const Frame frame(to_c / dist);
  const float phi = kTwoPi * u.y;
  const float sin_t = std::sqrt(sin2_t);
  const Vec3 wi = frame.to_world(Vec3(sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t));
  LightSample ls;
  ls.wi = glm::normalize(wi);
  ls.p = ctx.p + t * ls.wi;
  ls.n = glm::normalize(ls.p - c);
  ls.p = c + r * ls.n;
  ls.p_error = sphere_->position_error();
  ls.pdf = 1.0f / (kTwoPi * one_minus_cos_max);  // uniform over the cone's solid angle 2 pi (1 - cos theta_max)
  ls.radiance = emitted(radiance_, two_sided_, ls.n, -ls.wi);
  return ls;
}

bool SphereLight::aim_point(Vec3* p) const {
  *p = sphere_->center();
  return true;
}

// Normals in every direction; seen from anywhere outside, its intensity is π r² L.
LightBounds SphereLight::bounds() const {
  LightBounds b;
  b.lo = sphere_->center() - Vec3(sphere_->radius());
  b.hi = sphere_->center() + Vec3(sphere_->radius());
  b.cone = DirectionCone{Vec3(0, 0, 1), kPi, 0.5f * kPi};
  b.phi = average(radiance_) * kPi * sphere_->radius() * sphere_->radius();
  return b;
}

Rgb SphereLight::power() const { return radiance_ * (kPi * sphere_->primitive_area(0) * (two_sided_ ? 2.0f : 1.0f)); }

float SphereLight::pdf(const LightSampleContext& ctx, const LightHit& hit) const {
  if (!hit.si) return 0.0f;
  const SurfaceInteraction& si = *hit.si;
  const Vec3 to_c = sphere_->center() - ctx.p;
  const float dist2 = glm::dot(to_c, to_c);
  const float r = sphere_->radius();
  if (dist2 <= r * r * 1.0001f) return area_to_solid_angle(1.0f / sphere_->primitive_area(0), ctx.p, si.p, si.ng);
  // Only the near side is ever sampled; a far-side hit (possible from inside a two-sided sphere's
  // tangent region) keeps the cone density, which is what sample() would produce in that direction.
  const float sin2_max = r * r / dist2;
  const float cos_max = safe_sqrt(1.0f - sin2_max);
  return 1.0f / (kTwoPi * (sin2_max / (1.0f + cos_max)));
}

}  // namespace kozu
