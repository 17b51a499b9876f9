// dielectric: a smooth interface between the outside (front side) and a medium of IOR `ior`,
// reflecting and refracting with the unpolarised Fresnel equations; total internal reflection
// from inside. One lobe is chosen per sample with probability equal to its Fresnel weight.
//
// Parameters
//   ior  float  1.5  > 0  index of refraction of the inside relative to the outside
#pragma once

#include "materials/material.h"

namespace kozu {

class SmoothDielectricBsdf final : public Bsdf {
 public:
  explicit SmoothDielectricBsdf(float eta) : eta_(eta) {}
  Rgb eval(const Vec3&, const Vec3&, TransportMode) const override { return Rgb(0.0f); }
  BsdfSample sample(const Vec3& wo, float u_lobe, const Vec2& u, TransportMode mode) const override;
  float pdf(const Vec3&, const Vec3&) const override { return 0.0f; }
  uint32_t flags() const override { return kBsdfReflection | kBsdfTransmission | kBsdfSpecular; }

 private:
  float eta_;
};

class DielectricMaterial final : public Material {
 public:
  explicit DielectricMaterial(float ior) : ior_(ior) {}
  static std::unique_ptr<Material> create(const JsonObject& desc);
  const Bsdf* bsdf(const SurfaceInteraction& si, Arena& arena) const override;
  float ior() const { return ior_; }

 private:
  float ior_;
};

}  // namespace kozu
