// Diffuse area emitters on shapes: radiance L leaves the front side (both sides if two_sided). A ray meets
// them by hitting their shape (LightHit::si); eval is the same for all three, their pdfs differ.
//
//  TriangleLight  one triangle of a mesh; uniform area sampling (Heitz 2019 square->triangle map).
//  PolygonLight   a planar polygon (quad/polygon shapes) kept as one light: a fan triangle is
//                 picked by area, then a uniform point in it. Keeping the polygon whole is the
//                 seam for analytic (LTC) integration of polygonal lights.
//  SphereLight    samples the cone of directions the sphere subtends (uniform in solid angle),
//                 or the whole surface by area when the reference point is inside.
// Power: Phi = pi * A * L (x2 when two-sided).
#pragma once

#include "core/distribution.h"
#include "geometry/shape.h"
#include "lights/light.h"

#include <span>
#include <vector>

namespace kozu {

// Converts an area density at a light point to a solid-angle density at ref.
inline float area_to_solid_angle(float pdf_area, const Vec3& ref, const Vec3& p, const Vec3& n) {
  const Vec3 d = p - ref;
  const float dist2 = glm::dot(d, d);
  const float cos_l = std::abs(glm::dot(n, d)) / std::sqrt(dist2);
  return cos_l > 0.0f ? pdf_area * dist2 / cos_l : 0.0f;
}

// One emitting triangle, precomputed for sampling: p = p0 + b1 e1 + b2 e2.
struct EmitterTriangle {
  Vec3 p0, e1, e2;
  Vec3 n;  // unit geometric normal (front side)
  float area = 0;
  EmitterTriangle() = default;
  EmitterTriangle(const Vec3& a, const Vec3& b, const Vec3& c);
  AreaSample sample(const Vec2& u) const;
};

// What the three emitters share: constant radiance leaving one or both sides.
class DiffuseAreaLight : public Light {
 public:
  DiffuseAreaLight(const Rgb& radiance, bool two_sided) : radiance_(radiance), two_sided_(two_sided) {}
  Rgb eval(const LightHit& hit) const final;

 protected:
  Rgb radiance_;
  bool two_sided_;
};

class TriangleLight final : public DiffuseAreaLight {
 public:
  TriangleLight(const TriangleMesh* mesh, uint32_t prim, const Rgb& radiance, bool two_sided);
  LightSample sample(const LightSampleContext& ctx, const Vec2& u) const override;
  float pdf(const LightSampleContext& ctx, const LightHit& hit) const override;
  Rgb power() const override;

 private:
  EmitterTriangle tri_;
};

class PolygonLight final : public DiffuseAreaLight {
 public:
  // mesh holds the polygon's triangulation (all of its primitives belong to this light) and its corners in order.
  PolygonLight(const TriangleMesh* mesh, const Rgb& radiance, bool two_sided);
  LightSample sample(const LightSampleContext& ctx, const Vec2& u) const override;
  float pdf(const LightSampleContext& ctx, const LightHit& hit) const override;
  Rgb power() const override;
  const PolygonLight* as_polygon() const override { return this; }

  // For analytic integration (seed 003; integrators/path.cpp "direct": "ltc"):
  // the corners in order (world space), the front side's unit normal, the radiance, whether both sides emit;
  std::span<const Vec3> corners() const { return corners_; }
  const Vec3& normal() const { return triangles_[0].n; }
  const Rgb& radiance() const { return radiance_; }
  bool two_sided() const { return two_sided_; }
  // true when the LTC integral takes the polygon (at most Ltc::kMaxVertices corners);
  bool analytic() const;
  // radiance from the light towards ref (zero from behind a one-sided light);
  Rgb radiance_towards(const Vec3& ref) const;
  // where the ray from o along the unit d meets the polygon, if it does;
  bool intersect(const Vec3& o, const Vec3& d, Vec3* p) const;
  // and the solid-angle density of sample() at the point p of the polygon, seen from ref.
  float pdf_at(const Vec3& ref, const Vec3& p) const { return area_to_solid_angle(1.0f / area_, ref, p, normal()); }

 private:
  std::vector<Vec3> corners_;
  std::vector<EmitterTriangle> triangles_;
  AliasTable pick_;  // fan triangle by area
  // Parallelograms (most quads) are sampled directly: p0 + u e1 + v e2.
  bool parallelogram_ = false;
  Vec3 p0_, e1_, e2_;
  float area_;
};

class SphereLight final : public DiffuseAreaLight {
 public:
  SphereLight(const Sphere* sphere, const Rgb& radiance, bool two_sided);
  LightSample sample(const LightSampleContext& ctx, const Vec2& u) const override;
  float pdf(const LightSampleContext& ctx, const LightHit& hit) const override;
  Rgb power() const override;

 private:
  const Sphere* sphere_;
};

}  // namespace kozu
