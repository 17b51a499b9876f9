// diffuse: a two-sided diffuse reflector with a choice of BRDF (`model`): the Lambertian
// f = albedo / pi (default, this file), the Call of Duty: WWII multiple-scattering diffuse
// (cod_multiscatter_diffuse.h) or Shirley et al.'s diffuse term under a smooth coat (shirley_diffuse.h).
//
// Parameters
//   model        string  "lambert"  "lambert", "cod-multiscatter" or "shirley"
//   albedo       rgb     0.5        each in [0, 1]  rho: lambert's directional-hemispherical reflectance; or a
//                                   texture (textures/texture_parse.h; image values are clamped to [0, 1])
//   gloss        float   0.5        in [0, 1]  cod-multiscatter only; or `roughness`, `alpha`, `alpha_u`+
//                                   `alpha_v` (mapped to the WWII gloss, roughness.h), `gloss_model`; each may
//                                   be a texture (roughness.h: varying values in 1/255 steps)
//   f0           float   0.04       in [0, 1]  shirley only: the coat's normal-incidence reflectance; or a texture
// A key the chosen model does not read is an error. `distribution` (roughness.h) is rejected: no
// diffuse model has a microfacet distribution.
//
// Every model is sampled with the cosine-weighted hemisphere (Malley's method) on wo's side, so
// pdf = |cos theta_i| / pi; for lambert eval/pdf = albedo exactly.
#pragma once

#include "materials/material.h"
#include "materials/roughness.h"
#include "textures/texture.h"

#include <memory>

namespace kozu {

// Cosine-weighted hemisphere sampling on wo's side, shared by the diffuse models: fills wi, pdf and
// flags (reflection, diffuse) and leaves f to the caller. Invalid (pdf 0) when wo lies in the
// horizon or the sample lands on the disk's rim.
BsdfSample sample_cosine_lobe(const Vec3& wo, const Vec2& u);
inline float cosine_lobe_pdf(const Vec3& wo, const Vec3& wi) {
  return same_hemisphere(wo, wi) ? abs_cos_theta(wi) * kInvPi : 0.0f;
}

// The LTC lobe (Bsdf::ltc_lobes) of a diffuse model that is not Lambertian: the clamped cosine weighted by
// π f(wo, toward) / cos θ_toward, the albedo a Lambertian surface would need to match f towards the light.
int diffuse_ltc_lobe(const Bsdf& bsdf, const Vec3& wo, const Vec3& toward, LtcLobe* out);

class DiffuseBsdf final : public Bsdf {
 public:
  explicit DiffuseBsdf(const Rgb& albedo) : albedo_(albedo) {}
  Rgb eval(const Vec3& wo, const Vec3& wi, TransportMode mode) const override;
  BsdfSample sample(const Vec3& wo, float u_lobe, const Vec2& u, TransportMode mode) const override;
  float pdf(const Vec3& wo, const Vec3& wi) const override;
  Rgb eval_pdf(const Vec3& wo, const Vec3& wi, float* pdf_out, TransportMode mode) const override;
  uint32_t flags() const override { return kBsdfReflection | kBsdfDiffuse; }
  // Exact: albedo times the clamped cosine (Heitz et al. 2016 eq. 4), M = I.
  int ltc_lobes(const Vec3& wo, const Vec3& toward, LtcLobe* out) const override;

 private:
  Rgb albedo_;
};

enum class DiffuseModel { Lambert, CodMultiscatter, Shirley };

struct DiffuseParams {
  DiffuseModel model = DiffuseModel::Lambert;
  Rgb albedo{0.5f};
  float gloss = 0.5f;  // cod-multiscatter: the WWII gloss (Chan 2018 eq. (2))
  float f0 = 0.04f;    // shirley: the coat's normal-incidence Fresnel reflectance
};

class DiffuseMaterial final : public Material {
 public:
  explicit DiffuseMaterial(const Rgb& albedo) : params_{DiffuseModel::Lambert, albedo} {}
  explicit DiffuseMaterial(const DiffuseParams& params) : params_(params) {}
  // With a varying albedo (null: params.albedo), gloss (null: params.gloss) and f0 (null: params.f0).
  DiffuseMaterial(const DiffuseParams& params, std::unique_ptr<const Texture> albedo,
                  std::unique_ptr<const TexturedRoughness> gloss = nullptr, std::unique_ptr<const Texture> f0 = nullptr)
      : params_(params),
        albedo_texture_(std::move(albedo)),
        gloss_texture_(std::move(gloss)),
        f0_texture_(std::move(f0)) {}
  static Deferred<Material> parse(const JsonObject& desc, const MaterialParseContext& ctx);
  const Bsdf* bsdf(const SurfaceInteraction& si, Arena& arena) const override;
  bool may_be_specular() const override { return false; }
  const Rgb& albedo() const { return params_.albedo; }
  const DiffuseParams& params() const { return params_; }

 private:
  DiffuseParams params_;
  std::unique_ptr<const Texture> albedo_texture_;           // null: params_.albedo everywhere
  std::unique_ptr<const TexturedRoughness> gloss_texture_;  // cod-multiscatter; null: params_.gloss everywhere
  std::unique_ptr<const Texture> f0_texture_;               // shirley; null: params_.f0 everywhere
};

}  // namespace kozu
