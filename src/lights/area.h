// Diffuse area emitters on shapes: radiance L leaves the front side (both sides if two_sided). A ray meets
// them by hitting their shape (LightHit::si); eval is the same for all three, their pdfs differ.
//
//  TriangleLight  one triangle of a mesh; uniform area sampling (Heitz 2019 square->triangle map).
//  PolygonLight   a planar polygon (quad/polygon shapes) kept as one light: a fan triangle is
//                 picked by area, then a uniform point in it. Keeping the polygon whole is the
//                 seam for analytic (LTC) integration of polygonal lights. Its radiance may be a
//                 texture over the polygon's (u, v) (docs/lights.md): a parallelogram then samples
//                 points in proportion to the texture's luminance (a grid of kTexels² filtered
//                 lookups, with a floor so that every point keeps a density), and LTC shading
//                 fetches the texture prefiltered as Heitz et al. 2016 §5.3–5.4 (lights/ltc_texture.h).
//  SphereLight    samples the cone of directions the sphere subtends (uniform in solid angle),
//                 or the whole surface by area when the reference point is inside.
// Power: Phi = pi * A * L (x2 when two-sided).
#pragma once

#include "core/distribution.h"
#include "core/frame.h"
#include "geometry/shape.h"
#include "lights/light.h"
#include "lights/ltc_texture.h"
#include "textures/texture.h"

#include <array>
#include <memory>
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
  Rgb eval(const LightHit& hit) const override;
  const DiffuseAreaLight* as_area() const override { return this; }

  // For sampling by a BSDF's lobe (integrators/lobe_light_sampler.h): a flat emitter's triangles, empty for a sphere
  // and for polygons of more than Ltc::kMaxVertices corners;
  virtual std::span<const EmitterTriangle> flat_triangles() const { return {}; }
  // whether ref sees the emitting side of a flat emitter;
  virtual bool faces(const Vec3& /*ref*/) const { return true; }
  // the light seen from ctx.p along the unit wi, where that ray meets it: its point, normal and radiance, and the
  // solid-angle density of this light's own sample() there (false where the ray misses it).
  virtual bool along(const LightSampleContext& /*ctx*/, const Vec3& /*wi*/, LightSample* /*ls*/) const {
    return false;
  }

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
  LightBounds bounds() const override;
  void refit() override;
  bool aim_point(Vec3* p) const override {
    *p = tri_.p0 + (tri_.e1 + tri_.e2) * (1.0f / 3.0f);
    return true;
  }
  std::span<const EmitterTriangle> flat_triangles() const override { return {&tri_, 1}; }
  bool faces(const Vec3& ref) const override { return two_sided_ || glm::dot(tri_.n, ref - tri_.p0) > 0.0f; }
  bool along(const LightSampleContext& ctx, const Vec3& wi, LightSample* ls) const override;

 private:
  const TriangleMesh* mesh_;
  uint32_t prim_;
  EmitterTriangle tri_;
};

class PolygonLight final : public DiffuseAreaLight {
 public:
  // mesh holds the polygon's triangulation (all of its primitives belong to this light) and its corners in order.
  // texture (optional) multiplies radiance, looked up at the mesh's (u, v); negative and non-finite values read 0.
  PolygonLight(const TriangleMesh* mesh, const Rgb& radiance, bool two_sided,
               std::unique_ptr<const Texture> texture = nullptr);
  Rgb eval(const LightHit& hit) const override;
  LightSample sample(const LightSampleContext& ctx, const Vec2& u) const override;
  float pdf(const LightSampleContext& ctx, const LightHit& hit) const override;
  Rgb power() const override;
  LightBounds bounds() const override;
  const PolygonLight* as_polygon() const override { return this; }
  void refit() override;
  bool aim_point(Vec3* p) const override {
    *p = centre_;
    return true;
  }

  // For analytic integration (Heitz et al. 2016; integrators/path.cpp "direct": "ltc"):
  // the corners in order (world space), the front side's unit normal, whether both sides emit;
  std::span<const Vec3> corners() const { return corners_; }
  // the mean of its corners;
  const Vec3& centre() const { return centre_; }
  // its triangulation (world space);
  std::span<const EmitterTriangle> triangles() const { return triangles_; }
  const Vec3& normal() const { return triangles_[0].n; }
  bool two_sided() const { return two_sided_; }
  bool textured() const { return texture_ != nullptr; }
  // true when the LTC integral takes the polygon (at most Ltc::kMaxVertices corners);
  bool analytic() const;
  // whether ref sees the emitting side;
  bool faces(const Vec3& ref) const override { return two_sided_ || glm::dot(normal(), ref - corners_[0]) > 0.0f; }
  std::span<const EmitterTriangle> flat_triangles() const override {
    return analytic() ? std::span<const EmitterTriangle>(triangles_) : std::span<const EmitterTriangle>();
  }
  bool along(const LightSampleContext& ctx, const Vec3& wi, LightSample* ls) const override;
  // the radiance at the point p of the polygon (on the emitting side);
  Rgb radiance_at(const Vec3& p) const;
  // the radiance averaged over the polygon as the lobe ltc (in frame, at ref) sees it: I_L of Heitz et al. 2016 eq.
  // (14), exact for an untextured light, the prefiltered fetch of §5.4 for a textured one;
  Rgb ltc_radiance(const Ltc& ltc, const Frame& frame, const Vec3& ref) const;
  // where the ray from o along the unit d meets the polygon, if it does;
  bool intersect(const Vec3& o, const Vec3& d, Vec3* p) const;
  // the solid-angle density of sample() at the point p of the polygon, seen from ref;
  float pdf_at(const Vec3& ref, const Vec3& p) const { return area_to_solid_angle(area_pdf(p), ref, p, normal()); }
  // and sampling uniformly by area even where the light is textured, with its density ("ltc" subtracts a control
  // variate with a constant radiance: a density following the texture would give it the spikes the texture's dark
  // parts remove from L / p).
  LightSample sample(const LightSampleContext& ctx, const Vec2& u, bool by_luminance) const;
  float pdf_by_area_at(const Vec3& ref, const Vec3& p) const {
    return area_to_solid_angle(1.0f / area_, ref, p, normal());
  }

  // The texture grid's resolution (importance sampling, power, LTC prefiltering).
  static constexpr int kTexels = 256;

 private:
  Vec2 uv_at(const Vec3& p) const;
  Vec2 square_coordinates(const Vec3& p) const;  // (a, b) of p = p0 + a e1 + b e2
  float area_pdf(const Vec3& p) const;
  Rgb texture_value(const TextureQuery& q) const;
  void fit();  // everything derived from the mesh's geometry
  void prepare_texture();

  const TriangleMesh* mesh_;
  std::vector<Vec3> corners_;
  Vec3 centre_{0.0f};
  std::vector<EmitterTriangle> triangles_;
  std::vector<std::array<Vec2, 3>> triangle_uvs_;  // the corners' (u, v), as triangles_ orders them
  AliasTable pick_;                                // fan triangle by area
  // The polygon's square p0 + a e1 + b e2, (a, b) ∈ [0, 1]²: the polygon itself for a parallelogram (most quads,
  // sampled directly), else its bounding rectangle in its plane (set for textured lights only).
  bool parallelogram_ = false;
  Vec3 p0_, e1_, e2_;
  float area_;
  std::unique_ptr<const Texture> texture_;
  Rgb mean_texture_{0.0f};     // the radiance's mean over the square's texel grid
  Distribution2D texel_pick_;  // textured parallelograms: by luminance over the square
  std::unique_ptr<LtcTexture> ltc_texture_;
};

class SphereLight final : public DiffuseAreaLight {
 public:
  SphereLight(const Sphere* sphere, const Rgb& radiance, bool two_sided);
  LightSample sample(const LightSampleContext& ctx, const Vec2& u) const override;
  float pdf(const LightSampleContext& ctx, const LightHit& hit) const override;
  Rgb power() const override;
  LightBounds bounds() const override;
  bool aim_point(Vec3* p) const override;

 private:
  const Sphere* sphere_;
};

}  // namespace kozu
