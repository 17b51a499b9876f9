// A material turns a surface hit into a BSDF (allocated in the per-thread arena).
#pragma once

#include "core/arena.h"
#include "geometry/interaction.h"
#include "materials/bsdf.h"

#include <memory>
#include <string>

namespace kozu {

class JsonObject;

class Material {
 public:
  virtual ~Material() = default;
  // The BSDF at si, in si's shading frame. Lives until the arena is reset.
  virtual const Bsdf* bsdf(const SurfaceInteraction& si, Arena& arena) const = 0;
  // Seam for subsurface scattering: materials with a BSSRDF override this (see docs/architecture.md).
  virtual bool has_subsurface() const { return false; }

  std::string name;
};

// Builds a material from its JSON description, dispatching on "type" (registry.cpp).
std::unique_ptr<Material> make_material(const JsonObject& desc);

}  // namespace kozu
