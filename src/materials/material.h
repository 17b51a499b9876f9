// A material turns a surface hit into a BSDF (allocated in the per-thread arena).
#pragma once

#include "core/arena.h"
#include "core/registry.h"
#include "geometry/interaction.h"
#include "geometry/shape.h"
#include "materials/bsdf.h"
#include "materials/bump_map.h"
#include "materials/normal_map.h"
#include "materials/opacity_mask.h"
#include "materials/surface_occlusion_material.h"
#include "textures/texture.h"
#include "textures/texture_cache.h"

#include <functional>
#include <memory>
#include <string>

namespace kozu {

class JsonObject;
class RgbProfile;

class Material {
 public:
  virtual ~Material() = default;
  // The BSDF at si, in si's shading frame. Lives until the arena is reset.
  virtual const Bsdf* bsdf(const SurfaceInteraction& si, Arena& arena) const = 0;
  // BSSRDF materials (subsurface.h): the radial profile the integrator's probe rays sample, taken at the point si
  // where the camera path enters (a textured material's values there; lives until the arena is reset), and the
  // BSDF at the point si where light leaves the object. The camera-side BSDF's transmitted samples enter the
  // BSSRDF.
  virtual const RgbProfile* subsurface_profile(const SurfaceInteraction&, Arena&) const { return nullptr; }
  virtual const Bsdf* subsurface_exit_bsdf(const SurfaceInteraction&, Arena&) const { return nullptr; }
  virtual bool has_subsurface() const { return false; }
  // Whether a BSDF it makes may have a specular (Dirac) lobe at some point: false lets the paths of the visible
  // emission alone (PathIntegrator::visible_emission) end at its surfaces without building a BSDF. True unless a
  // material knows better.
  virtual bool may_be_specular() const { return true; }

  // Replaces si's shading frame by the normal or bump map's (none: unchanged). The integrator calls it before
  // bsdf().
  void perturb_shading(SurfaceInteraction& si) const {
    if (normal_map)
      normal_map->apply(si);
    else if (bump_map)
      bump_map->apply(si);
  }
  bool perturbs_shading() const { return normal_map || bump_map; }

  std::string name;
  // Keys every surface material accepts (parse_material, docs/scene-format.md); null: none.
  std::unique_ptr<const NormalMap> normal_map;
  std::unique_ptr<const BumpMap> bump_map;
  std::unique_ptr<const OpacityMask> opacity;  // null: opaque (also for "opacity": 1)
  // Chan 2018 §4 material surface occlusion (materials/surface_occlusion_material.h); null: off.
  std::unique_ptr<const SurfaceOcclusion> surface_occlusion;
};

// The texture lookup at a hit: its (u, v) and the footprint of the ray cone that found it (geometry/shape.h,
// geometry/ray_cone.h).
inline TextureQuery texture_query(const SurfaceInteraction& si) {
  TextureQuery q;
  q.uv = si.uv;
  uv_footprint(si, &q.duvdx, &q.duvdy);
  q.fine = si.fine_filtering;
  return q;
}

// What material parsers need besides their JSON: the texture cache image textures are read through.
struct MaterialParseContext {
  std::function<TextureCache*()> textures;  // made on first use; empty: image textures are refused
};

// Parses a material's JSON description by its "type" (registry.cpp, core/registry.h).
Deferred<Material> parse_material(const JsonObject& desc, const MaterialParseContext& ctx);

}  // namespace kozu
