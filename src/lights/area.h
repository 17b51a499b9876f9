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

#include <vector>

namespace kozu {

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
  // mesh holds the polygon's triangulation (all of its primitives belong to this light).
  PolygonLight(const TriangleMesh* mesh, const Rgb& radiance, bool two_sided);
  LightSample sample(const LightSampleContext& ctx, const Vec2& u) const override;
  float pdf(const LightSampleContext& ctx, const LightHit& hit) const override;
  Rgb power() const override;

 private:
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

// Converts an area density at a light point to a solid-angle density at ref.
inline float area_to_solid_angle(float pdf_area, const Vec3& ref, const Vec3& p, const Vec3& n) {
  const Vec3 d = p - ref;
  const float dist2 = glm::dot(d, d);
  const float cos_l = std::abs(glm::dot(n, d)) / std::sqrt(dist2);
  return cos_l > 0.0f ? pdf_area * dist2 / cos_l : 0.0f;
}

}  // namespace kozu
