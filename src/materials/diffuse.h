// diffuse: the Lambertian BRDF f = albedo / pi, two-sided.
//
// Parameters
//   albedo  rgb  default 0.5  each in [0, 1]  directional-hemispherical reflectance
//
// Sampled with the cosine-weighted hemisphere (Malley's method), so eval/pdf = albedo exactly.
#pragma once

#include "materials/material.h"

namespace kozu {

class DiffuseBsdf final : public Bsdf {
 public:
  explicit DiffuseBsdf(const Rgb& albedo) : albedo_(albedo) {}
  Rgb eval(const Vec3& wo, const Vec3& wi, TransportMode mode) const override;
  BsdfSample sample(const Vec3& wo, float u_lobe, const Vec2& u, TransportMode mode) const override;
  float pdf(const Vec3& wo, const Vec3& wi) const override;
  Rgb eval_pdf(const Vec3& wo, const Vec3& wi, float* pdf_out, TransportMode mode) const override;
  uint32_t flags() const override { return kBsdfReflection | kBsdfDiffuse; }

 private:
  Rgb albedo_;
};

class DiffuseMaterial final : public Material {
 public:
  explicit DiffuseMaterial(const Rgb& albedo) : albedo_(albedo) {}
  static std::unique_ptr<Material> create(const JsonObject& desc);
  const Bsdf* bsdf(const SurfaceInteraction& si, Arena& arena) const override;
  const Rgb& albedo() const { return albedo_; }

 private:
  Rgb albedo_;
};

}  // namespace kozu
