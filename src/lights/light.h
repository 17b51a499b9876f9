// Light interface. Three families, told apart by type so the integrator needs no casts:
//  - AreaLight: emission attached to shape primitives, found by ray hits (radiance(si)).
//  - InfiniteLight: radiance arriving from directions no geometry blocks (radiance(dir)).
//  - delta lights (point, spot): reachable only by sampling.
// All pdfs are per unit solid angle at the reference point; delta lights report pdf 1 and delta.
#pragma once

#include "core/color.h"
#include "geometry/interaction.h"

namespace kozu {

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

class Light {
 public:
  virtual ~Light() = default;
  virtual LightSample sample(const LightSampleContext& ctx, const Vec2& u) const = 0;
  // Emitted power (W), used to choose lights in proportion to it.
  virtual Rgb power() const = 0;
  virtual bool is_delta() const { return false; }
  // Called once the scene's bounding sphere is known (infinite lights need its radius).
  virtual void preprocess(const Vec3& /*scene_center*/, float /*scene_radius*/) {}

  uint32_t index = 0;  // position in the scene's light list (for the selection pmf)
};

class AreaLight : public Light {
 public:
  // Radiance leaving the hit point towards si.wo.
  virtual Rgb radiance(const SurfaceInteraction& si) const = 0;
  // Density with which sample(ctx, .) would have produced the direction to si.
  virtual float pdf(const LightSampleContext& ctx, const SurfaceInteraction& si) const = 0;
};

class InfiniteLight : public Light {
 public:
  // Radiance arriving from direction dir (world space, pointing away from the scene).
  virtual Rgb radiance(const Vec3& dir) const = 0;
  virtual float pdf(const LightSampleContext& ctx, const Vec3& dir) const = 0;
};

}  // namespace kozu
