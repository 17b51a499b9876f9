// Light interface: every light is sampled (`sample`), evaluated where a ray met it (`eval`) and asked for the
// density of that direction (`pdf`) through the same three functions, so the integrator never needs to know
// which kind it holds. The kinds differ only in where a ray meets them:
//  - area lights (lights/area.h): emission attached to shape primitives, met by ray hits (LightHit::si set);
//  - infinite lights (lights/environment.h, lights/directional.h, is_infinite()): met by rays that escape the
//    scene (si null);
//  - delta lights (point, spot, a directional light of diameter 0; is_delta()): never met by a ray; reachable only
//    by sampling (eval and pdf 0).
// All pdfs are per unit solid angle at the reference point; delta lights' samples report pdf 1.
#pragma once

#include "core/color.h"
#include "core/registry.h"
#include "geometry/interaction.h"
#include "lights/light_bounds.h"

namespace kozu {

class PolygonLight;
class DiffuseAreaLight;

// Where a light is sampled from. n is the surface normal there, or zero for points in a medium
// (a light may use it to sample only the visible hemisphere).
struct LightSampleContext {
  Vec3 p;
  Vec3 n{0.0f};
  static LightSampleContext from(const SurfaceInteraction& si) { return {si.p, si.shading.n}; }
};

struct LightSample {
  Rgb radiance{0.0f};  // incident radiance at ctx.p along -wi (before visibility)
  Vec3 wi;             // unit direction from ctx.p towards the light
  float pdf = 0;       // solid-angle density (1 for delta lights)
  Vec3 p;              // point on the light (for the shadow ray); unused for infinite lights
  Vec3 n{0.0f};        // light surface normal at p (zero for point-like and infinite lights)
  float p_error = 0;   // error bound of p along n (SurfaceInteraction::p_error)
  bool infinite = false;
  bool valid() const { return pdf > 0.0f; }
};

// Where a ray from a reference point met a light.
struct LightHit {
  Vec3 wi;                                 // unit direction from the reference point towards the light
  const SurfaceInteraction* si = nullptr;  // the emitting surface point (area lights); null for an escaped ray
};

class Light {
 public:
  virtual ~Light() = default;
  virtual LightSample sample(const LightSampleContext& ctx, const Vec2& u) const = 0;
  // Radiance arriving at the reference point along -hit.wi from where the ray met the light.
  virtual Rgb eval(const LightHit& hit) const = 0;
  // Density with which sample(ctx, .) would have produced hit's direction (and point).
  virtual float pdf(const LightSampleContext& ctx, const LightHit& hit) const = 0;
  // eval(hit) and pdf(ctx, hit) at once, for the light a BSDF sample met (an environment maps the direction to its
  // image once for both); the density is left 0 where the radiance is black (nothing to weigh).
  virtual Rgb eval_pdf(const LightSampleContext& ctx, const LightHit& hit, float* pdf) const {
    const Rgb L = eval(hit);
    *pdf = is_black(L) ? 0.0f : this->pdf(ctx, hit);
    return L;
  }
  // Emitted power (W), used to choose lights in proportion to it.
  virtual Rgb power() const = 0;
  // Where and how it emits, for the light hierarchy (lights/light_tree.h): phi is the emitter's intensity scale,
  // so that the importance of a cluster approximates the irradiance it gives (area lights A L, point and spot lights
  // their peak intensity); infinite lights report their irradiance (environment π L̄, distant light E).
  virtual LightBounds bounds() const = 0;
  // Where distance sampling in a homogeneous medium aims (equiangular sampling, media/equiangular.h): the emitter's
  // position or centroid, a point that does not depend on the shading point; false for infinite lights.
  virtual bool aim_point(Vec3* /*p*/) const { return false; }
  // This light as a polygon light (lights/area.h), or null.
  virtual const PolygonLight* as_polygon() const { return nullptr; }
  // This light as an emitter on a shape (lights/area.h), or null.
  virtual const DiffuseAreaLight* as_area() const { return nullptr; }
  virtual bool is_delta() const { return false; }
  virtual bool is_infinite() const { return false; }
  // Called once the scene's bounding sphere is known (infinite lights need its radius).
  virtual void preprocess(const Vec3& /*scene_center*/, float /*scene_radius*/) {}
  // The shape under an area light was posed anew (an animation's keys, Scene::pose_shapes): recomputes what the
  // light derived from the shape's geometry.
  virtual void refit() {}

  uint32_t index = 0;  // position in the scene's light list (for the selection pmf)
  // An environment's "camera_visible": false: camera rays that escape see black (a transparent film's background),
  // while the light still lights the scene.
  bool camera_visible = true;
};

// Point-like emitters (point, spot): no ray meets them, so eval and pdf are 0.
class DeltaLight : public Light {
 public:
  Rgb eval(const LightHit&) const final { return Rgb(0.0f); }
  float pdf(const LightSampleContext&, const LightHit&) const final { return 0.0f; }
  bool is_delta() const final { return true; }
};

// Parses a light of the scene's "lights" list by its "type" (lights/registry.cpp).
Deferred<Light> parse_light(const JsonObject& desc, std::string* type = nullptr);

}  // namespace kozu
