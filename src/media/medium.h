// The participating-medium interface used by the path integrator (src/integrators/path.cpp).
//
// A medium gives, at a point p and for light travelling along the unit direction d, the extinction and
// scattering coefficients per color channel (direction-dependent for microflake media: Heitz et al. 2015 eqs. 2–3,
// σt(ω) = ρ σ(ω), σs(ω) = α ρ σ(ω)), its phase function, and majorants: piecewise-constant upper bounds
// of σt over all channels and directions along a ray, so that free-flight sampling (delta tracking) and
// transmittance estimation (ratio tracking) only take steps where there is matter (a coarse majorant grid
// for heterogeneous media; one segment for homogeneous ones).
//
// Media live inside shapes: a shape's `interior` medium fills its inside (the side opposite its front
// normal), `exterior` its outside; a shape without a material is an index-matched (invisible) boundary.
#pragma once

#include "core/arena.h"
#include "core/color.h"
#include "core/registry.h"
#include "media/phase.h"

#include <cstddef>
#include <memory>
#include <string>
#include <type_traits>

namespace kozu {

struct MediumProperties {
  Rgb sigma_t{0.0f};
  Rgb sigma_s{0.0f};
};

// Receives the majorant segments of a ray in order; returns false to stop the traversal.
class MajorantVisitor {
 public:
  virtual bool segment(float t0, float t1, float majorant) = 0;

 protected:
  ~MajorantVisitor() = default;
};

class Medium {
 public:
  virtual ~Medium() = default;
  virtual MediumProperties properties(const Vec3& p, const Vec3& d) const = 0;
  // The phase function at p; it may be allocated in the arena (valid until the arena is reset).
  virtual const PhaseFunction* phase(const Vec3& p, Arena& arena) const = 0;
  // Visits the majorant segments of o + t d for t in [t0, t1] (d a unit vector), in order of t.
  virtual void majorants(const Vec3& o, const Vec3& d, float t0, float t1, MajorantVisitor& visitor) const = 0;
  // The constant coefficients of a homogeneous medium, whose flights have closed-form densities
  // (media/homogeneous_flight.h) that the path tracer weighs against equiangular sampling; null for others.
  virtual const MediumProperties* homogeneous() const { return nullptr; }
  // The fewest tentative collisions ratio tracking (media/tracking.h) takes per majorant segment: where a segment's
  // own majorant expects fewer, ratio tracking raises it (any majorant at or above σt keeps the estimate unbiased,
  // and a higher one lowers its variance). Worth it where a lookup is cheap beside the walk through the majorant
  // cells, as in density grids; 0 (the default) keeps the majorants.
  virtual float ratio_tracking_min_collisions() const { return 0.0f; }
  // The camera's position and its pixel's footprint, width + distance × angle (scene units, radians), for media
  // with levels of detail. Called by
  // the scene loader and again when the resolution changes (Scene::set_media_view).
  virtual void set_view(const Vec3& /*eye*/, float /*pixel_width*/, float /*pixel_angle*/) {}
  // What the last set_view could not honour (e.g. a level of detail beyond the chain), for a warning; empty if
  // nothing.
  virtual std::string view_warning() const { return {}; }
  // Level of detail per lookup: the medium to use where a ray's cone (geometry/ray_cone.h) is `width` wide (scene
  // units), with the widths [width_lo, width_hi) it serves. Tracking (media/tracking.h) splits a ray where its cone
  // leaves that range, so each part is tracked against one level's own majorants and an estimate stays unbiased for
  // the medium it walks. Media without levels serve every width themselves.
  struct Lod {
    const Medium* medium;
    float width_lo, width_hi;
  };
  virtual Lod level_for(float /*width*/) const { return {this, 0.0f, kInfinity}; }
  // For `kozu render --stats`: the level of detail in use (-1: the medium has none) and the bytes its voxel
  // data and its majorant grids hold (0 for analytic media).
  struct Stats {
    int lod = -1;                // per lookup: the camera's level (the finest camera rays take near the grid)
    size_t bytes = 0;           // voxels, every level
    size_t majorant_bytes = 0;  // majorant grids (media/majorant_grid.h)
    const char* lod_mode = "";  // "auto" (per lookup), "view" or "fixed"; empty without levels
  };
  virtual Stats stats() const { return {}; }

  std::string name;
};

// A MajorantVisitor from a callable bool(float t0, float t1, float majorant).
template <class F>
class MajorantLambda final : public MajorantVisitor {
 public:
  explicit MajorantLambda(F& f) : f_(f) {}
  bool segment(float t0, float t1, float majorant) override { return f_(t0, t1, majorant); }

 private:
  F& f_;
};
template <class F>
void for_each_majorant(const Medium& m, const Vec3& o, const Vec3& d, float t0, float t1, F&& f) {
  MajorantLambda<std::remove_reference_t<F>> v(f);
  m.majorants(o, d, t0, t1, v);
}

}  // namespace kozu

namespace kozu {
// Parses a medium's JSON description by its "type" (media/registry.cpp, core/registry.h); voxel files are read
// by the returned job, in the load phase.
Deferred<Medium> parse_medium(const JsonObject& desc);
}  // namespace kozu
