// plastic: a dielectric coat (rough or smooth) over a diffuse base, with Kelemen's coupled matte term
// in place of the base's explicit interreflections, so the sum conserves energy and is reciprocal.
//
// Citation: Kelemen & Szirmay-Kalos 2001, "A Microfacet Based Coupled Specular-Matte BRDF Model with
// Importance Sampling", as derived in
// ushiostarfish 2018 (blog posts on ushiostarfish's diary: "エネルギー保存Microfacet BRDF", "Microfacet入門"); the coat
// is the reflection lobe of the rough dielectric (dielectric.h). Equation map (ushiostarfish 2018, "[Kelemen 2001]
// のアプローチ"):
//   f          = f_spec + f_matte
//   f_spec     = F(ωh·ωo) G2 D(ωh) / (4 |cos θi| |cos θo|)         the coat's reflection
//   E_R(μ)     = ∫ f_spec cos θi dωi                              its albedo, baked with the dielectric Fresnel
//                                                                ("ベイクするときに誘導体フレネルを含んだ場合")
//   f_matte    = k (1 − E_R(μi)) (1 − E_R(μo)) / (π (1 − E_R,avg)) directional albedo k (1 − E_R(μo))
//   P_spec     = E_R(μo) / (E_R(μo) + k̃ (1 − E_R(μo)))            lobe selection, k̃ = mean of k
//   the matte lobe is sampled ∝ (1 − E_R(μi)) cos θi (CoupledLobe)
// A smooth coat (no roughness given, or α < 1e-3) is a Dirac reflection with E_R(μ) = F(μ).
// E_R comes from the checked-in tables (microfacet_albedo.h), linearly interpolated; the albedo is
// therefore E_R,true(μo) + k (1 − E_R,table(μo)), equal to 1 for k = 1 to the tables' accuracy.
//
// Parameters
//   albedo   rgb    0.5   in [0, 1]  k, the base's reflectance; may be a texture (a colour; clamped to [0, 1])
//   ior      float  1.5   >= 1       the coat's IOR
//   roughness/alpha/alpha_u+alpha_v/gloss, distribution, gloss_model: roughness.h (default roughness 0.3);
//            each may be a texture (then the coat is rough; E_R tables per 1/255 step)
#pragma once

#include "materials/material.h"
#include "materials/microfacet.h"
#include "materials/microfacet_albedo.h"
#include "materials/roughness.h"
#include "materials/roughness_tables.h"

namespace kozu {

struct PlasticTables {
  AlbedoCurve e_r;  // the coat's reflection albedo E_R(μ)
  CoupledLobe lobe;
  // The tables of a rough coat of roughness alpha (isotropic; the RMS α of an anisotropic one) and IOR ior.
  static PlasticTables make_rough(MicrofacetType type, float alpha, float ior);
};

class PlasticBsdf final : public JointBsdf {
 public:
  // smooth: the coat is a Dirac reflection (d unused).
  PlasticBsdf(const MicrofacetDistribution& d, bool smooth, float eta, const Rgb& k, const PlasticTables* tables)
      : d_(d), smooth_(smooth), eta_(eta), k_(k), tables_(tables) {}
  BsdfSample sample(const Vec3& wo, float u_lobe, const Vec2& u, TransportMode mode) const override;
  Rgb eval_pdf(const Vec3& wo, const Vec3& wi, float* pdf_out, TransportMode mode) const override;
  uint32_t flags() const override { return kBsdfReflection | kBsdfDiffuse | (smooth_ ? kBsdfSpecular : kBsdfGlossy); }
  // A rough coat: the specular table's lobe (lights/ltc_table.h, fitted at IOR 1.5) weighted by this coat's exact
  // albedo E_R(μo); the matte term as a clamped cosine weighted by its exact albedo k (1 − E_R(μo)).
  int ltc_lobes(const Vec3& wo, const Vec3& toward, LtcLobe* out) const override;
  float narrowest_ltc_alpha() const override { return smooth_ ? 1.0f : std::sqrt(d_.alpha_x() * d_.alpha_y()); }

 private:
  float spec_probability(float e_o) const;
  MicrofacetDistribution d_;
  bool smooth_;
  float eta_;
  Rgb k_;
  const PlasticTables* tables_;
};

class PlasticMaterial final : public Material {
 public:
  PlasticMaterial(const Rgb& k, float ior, bool smooth, const MicrofacetDistribution& d);
  // Keys given as textures (null: the plain value).
  struct Textures {
    std::unique_ptr<const Texture> albedo;
    std::unique_ptr<const TexturedRoughness> roughness;  // with it the coat is rough (smooth and d unused)
  };
  PlasticMaterial(const Rgb& k, float ior, bool smooth, const MicrofacetDistribution& d, Textures textures);
  static Deferred<Material> parse(const JsonObject& desc, const MaterialParseContext& ctx);
  const Bsdf* bsdf(const SurfaceInteraction& si, Arena& arena) const override;
  bool may_be_specular() const override { return smooth_; }  // the coat's Dirac reflection

 private:
  Rgb k_;
  float ior_;
  bool smooth_;
  MicrofacetDistribution d_;
  PlasticTables tables_;
  // Textured roughness: the distribution per hit, the tables per level (null / unused otherwise).
  std::unique_ptr<const TexturedRoughness> rough_tex_;
  RoughnessTables<PlasticTables> tex_tables_;
  std::unique_ptr<const Texture> albedo_tex_;
};

}  // namespace kozu
