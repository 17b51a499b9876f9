// A material turns a surface hit into a BSDF (allocated in the per-thread arena).
#pragma once

#include "core/arena.h"
#include "core/registry.h"
#include "geometry/interaction.h"
#include "materials/bsdf.h"

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
  // BSSRDF materials (subsurface.h): the radial profile the integrator's probe rays sample, and the
  // BSDF where light leaves the object. The camera-side BSDF's transmitted samples enter the BSSRDF.
  virtual const RgbProfile* subsurface_profile() const { return nullptr; }
  virtual const Bsdf* subsurface_exit_bsdf(Arena&) const { return nullptr; }
  bool has_subsurface() const { return subsurface_profile() != nullptr; }

  std::string name;
};

// Parses a material's JSON description by its "type" (registry.cpp, core/registry.h).
Deferred<Material> parse_material(const JsonObject& desc);

}  // namespace kozu
