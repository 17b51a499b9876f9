// conductor: a smooth metal mirror with the exact conductor Fresnel term (fresnel.h).
//
// Parameters (at most one of `metal` or `eta`/`k`)
//   metal  string  -     named metal from metal_data.h ("Au", "gold", ...)
//   eta    rgb     -     real part of the complex IOR at 650/550/450 nm, > 0
//   k      rgb     0     imaginary part (extinction), >= 0
// With neither, F = 1 (a perfect mirror; used by white-furnace tests).
// Rough conductors (microfacet) extend this file's parameters with `roughness`/`alpha`.
#pragma once

#include "materials/material.h"

namespace kozu {

class SmoothConductorBsdf final : public Bsdf {
 public:
  SmoothConductorBsdf(const Rgb& eta, const Rgb& k, bool perfect) : eta_(eta), k_(k), perfect_(perfect) {}
  Rgb eval(const Vec3&, const Vec3&, TransportMode) const override { return Rgb(0.0f); }
  BsdfSample sample(const Vec3& wo, float u_lobe, const Vec2& u, TransportMode mode) const override;
  float pdf(const Vec3&, const Vec3&) const override { return 0.0f; }
  uint32_t flags() const override { return kBsdfReflection | kBsdfSpecular; }

 private:
  Rgb eta_, k_;
  bool perfect_;
};

class ConductorMaterial final : public Material {
 public:
  ConductorMaterial(const Rgb& eta, const Rgb& k, bool perfect) : eta_(eta), k_(k), perfect_(perfect) {}
  static std::unique_ptr<Material> create(const JsonObject& desc);
  const Bsdf* bsdf(const SurfaceInteraction& si, Arena& arena) const override;

 private:
  Rgb eta_, k_;
  bool perfect_;
};

}  // namespace kozu
