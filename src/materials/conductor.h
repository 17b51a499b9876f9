// conductor: a metal surface, smooth (a mirror) or rough (a GGX/Beckmann microfacet BRDF), with the
// conductor Fresnel term per RGB channel and optional multiple-scattering energy compensation.
//
// Citations: Walter, Marschner, Li, Torrance 2007 (microfacet BRDF with Smith masking); Heitz 2014
// (height-correlated G2); Kulla & Conty 2017 and Kelemen & Szirmay-Kalos 2001 as presented in
// ushiostarfish 2018 (blog posts on ushiostarfish's diary: "エネルギー保存Microfacet BRDF", "Microfacet入門")
// (compensation); Heitz et al. 2016 (stochastic). Equation map (ushiostarfish 2018):
//   f_spec = F(ωh·ωi) G2(ωi, ωo) D(ωh) / (4 |cos θi| |cos θo|)       Kelemen §"[Kelemen 2001] のアプローチ"
//   f_ms   = F_ms (1 − E(μo))(1 − E(μi)) / (π (1 − E_avg))          the coupled matte term with k = F_ms
//   F_avg  = 2 ∫ F(μ) μ dμ                                            "多重拡散項の近似"
//   F_ms   = F_avg² E_avg / (1 − F_avg (1 − E_avg))  ("series", default)  or  F_avg  ("average", ushiostarfish 2018's
//   choice) P_spec = E(μo), P_ms = 1 − E(μo)                                  lobe selection (導体想定, Fresnel not
//   baked) F(n, k, θ): exact (Born & Wolf) or pbrt-v2's approximation (r⊥, r∥ from n² + k²; fresnel.h)
//
// Parameters
//   metal          string  -        named metal (metal_data.h: Au, Ag, Cu, Al, Cr, Ti, Fe, Ni, Pt, W, Pb)
//   eta, k         rgb     -, 0     complex IOR at 650/550/450 nm; with neither metal nor eta, F = 1; each may be a
//                                   texture (read as data, no colour decoding: they are optical constants, not
//                                   reflectances; eta clamped to ≥ 1e-4, k to ≥ 0); the Fresnel term is then built
//                                   per hit, and in the compensated mode so is F_avg (the same 16-point Gauss–
//                                   Legendre rule as for constants, albedo::fresnel_average) and F_ms
//   fresnel        string  "exact"  "exact" or "approximate" (ushiostarfish 2018's formula)
//   roughness/alpha/alpha_u+alpha_v/gloss, distribution, gloss_model: roughness.h; none = smooth mirror;
//                  each may be a texture (then the surface is rough; compensation tables per 1/255 step)
//   multiscatter   string  "none"   "none" | "compensated" | "stochastic"
//   ms_fresnel     string  "series"  "series" (Kulla–Conty's geometric series) or "average" (F_avg)
// Deviations: anisotropic surfaces look E up at the RMS α = sqrt((αu² + αv²)/2) (the tables are
// isotropic); the compensation is then approximate: albedo 0.984–1.016 for (0.1, 0.5), where
// sqrt(αu αv) left it up to 11 % short (tests/materials/test_rough_materials.cpp).
#pragma once

#include "materials/fresnel.h"
#include "materials/material.h"
#include "materials/microfacet.h"
#include "materials/microfacet_albedo.h"
#include "materials/roughness.h"
#include "materials/roughness_tables.h"

namespace kozu {

enum class MultiscatterMode { None, Compensated, Stochastic };

class SmoothConductorBsdf final : public Bsdf {
 public:
  explicit SmoothConductorBsdf(const ConductorFresnel* fresnel) : fresnel_(fresnel) {}
  Rgb eval(const Vec3&, const Vec3&, TransportMode) const override { return Rgb(0.0f); }
  BsdfSample sample(const Vec3& wo, float u_lobe, const Vec2& u, TransportMode mode) const override;
  float pdf(const Vec3&, const Vec3&) const override { return 0.0f; }
  uint32_t flags() const override { return kBsdfReflection | kBsdfSpecular; }

 private:
  const ConductorFresnel* fresnel_;
};

// Per-material precomputation of the compensated mode (E curve, lobe sampler, F_ms).
struct ConductorCompensation {
  AlbedoCurve e;
  CoupledLobe lobe;
  Rgb f_ms{1.0f};
  // ushiostarfish 2018's F_ms from F_avg and E_avg ("series" or "average"; see the header).
  static Rgb multiple_fresnel(const Rgb& f_avg, float e_avg, bool series);
  // The tables of roughness alpha (isotropic; E looked up at the RMS α) for the Fresnel term fresnel.
  static ConductorCompensation make(MicrofacetType type, float alpha, const ConductorFresnel& fresnel, bool series);
};

// The LTC lobe (lights/ltc_table.h) of a rough conductor seen from wo, GGX or Beckmann at α: single scattering with
// Schlick's Fresnel from f0, weight F0 n + (1 − F0) n_F (Heitz et al. 2016 §4), and ushiostarfish 2018's coupled lobe
// of albedo `coupled` (0 without compensation). With compensation from kLtcCompensatedMinAlpha up, one lobe of the
// compensated table carries both weights; otherwise the single-scattering table's lobe, and `coupled` is added to
// *cosine, the weight of a clamped cosine. Shared by the conductor and standard's metal.
LtcLobe conductor_ltc_lobe(MicrofacetType type, const Vec3& wo, float alpha, const Rgb& f0, bool compensated,
                           const Rgb& coupled, Rgb* cosine);

// Single scattering plus (optionally) the compensated coupled lobe. Two-sided: a wo below the
// horizon mirrors the configuration.
class RoughConductorBsdf final : public Bsdf {
 public:
  RoughConductorBsdf(const MicrofacetDistribution& d, const ConductorFresnel* fresnel,
                     const ConductorCompensation* comp)
      : d_(d), fresnel_(fresnel), comp_(comp), f_ms_(comp ? comp->f_ms : Rgb(1.0f)) {}
  // With the hit's own F_ms (a textured eta or k) in place of comp's.
  RoughConductorBsdf(const MicrofacetDistribution& d, const ConductorFresnel* fresnel,
                     const ConductorCompensation* comp, const Rgb& f_ms)
      : d_(d), fresnel_(fresnel), comp_(comp), f_ms_(f_ms) {}
  Rgb eval(const Vec3& wo, const Vec3& wi, TransportMode mode) const override;
  BsdfSample sample(const Vec3& wo, float u_lobe, const Vec2& u, TransportMode mode) const override;
  float pdf(const Vec3& wo, const Vec3& wi) const override;
  Rgb eval_pdf(const Vec3& wo, const Vec3& wi, float* pdf_out, TransportMode mode) const override;
  uint32_t flags() const override { return kBsdfReflection | kBsdfGlossy; }
  // The fitted lobe (lights/ltc_table.h) at the geometric-mean α: the single-scattering table's, weighted by
  // Schlick's Fresnel from F(1), F0 n + (1 − F0) n_F; with compensation, the coupled lobe added as a clamped cosine
  // of its exact albedo F_ms (1 − E(μo)), or, from kLtcCompensatedMinAlpha up, one lobe: the compensated table's
  // shape with the sum of the two weights.
  int ltc_lobes(const Vec3& wo, const Vec3& toward, LtcLobe* out) const override;
  float narrowest_ltc_alpha() const override { return std::sqrt(d_.alpha_x() * d_.alpha_y()); }

 private:
  MicrofacetDistribution d_;
  const ConductorFresnel* fresnel_;
  const ConductorCompensation* comp_;  // null for "none"
  Rgb f_ms_;
};

// The Heitz et al. 2016 random walk (microsurface_walk.h). eval and sample are unbiased stochastic
// estimates seeded from their arguments; pdf is a proxy (single-scattering VNDF mixed with a cosine
// lobe) used only for MIS weights, which stay a partition of unity, so the estimator is unbiased.
class StochasticConductorBsdf final : public Bsdf {
 public:
  StochasticConductorBsdf(const MicrofacetDistribution& d, const ConductorFresnel* fresnel)
      : d_(d), fresnel_(fresnel) {}
  Rgb eval(const Vec3& wo, const Vec3& wi, TransportMode mode) const override;
  BsdfSample sample(const Vec3& wo, float u_lobe, const Vec2& u, TransportMode mode) const override;
  float pdf(const Vec3& wo, const Vec3& wi) const override;
  uint32_t flags() const override { return kBsdfReflection | kBsdfGlossy; }

 private:
  MicrofacetDistribution d_;
  const ConductorFresnel* fresnel_;
};

class ConductorMaterial final : public Material {
 public:
  static Deferred<Material> parse(const JsonObject& desc, const MaterialParseContext& ctx);
  const Bsdf* bsdf(const SurfaceInteraction& si, Arena& arena) const override;
  bool may_be_specular() const override { return smooth_; }  // a textured roughness is always rough

  // For tests and tools: a rough conductor built from code.
  ConductorMaterial(const ConductorFresnel& fresnel, bool smooth, const MicrofacetDistribution& d,
                    MultiscatterMode mode, bool series_fresnel = true);
  // Keys given as textures (null: the plain value).
  struct Textures {
    std::unique_ptr<const TexturedRoughness> roughness;  // with it the surface is rough (smooth and d unused)
    std::unique_ptr<const Texture> eta, k;               // replace fresnel's eta, k (fresnel.perfect must be false)
  };
  ConductorMaterial(const ConductorFresnel& fresnel, bool smooth, const MicrofacetDistribution& d,
                    MultiscatterMode mode, bool series_fresnel, Textures textures);

 private:
  ConductorFresnel fresnel_;
  bool smooth_ = true;
  MicrofacetDistribution d_;
  MultiscatterMode mode_ = MultiscatterMode::None;
  bool series_ = true;
  ConductorCompensation comp_;
  // Textured roughness: the distribution per hit, the compensation tables per level (null / unused otherwise).
  std::unique_ptr<const TexturedRoughness> rough_tex_;
  RoughnessTables<ConductorCompensation> tex_comp_;
  std::unique_ptr<const Texture> eta_tex_, k_tex_;  // textured eta / k (null otherwise)
};

// Parses "none" / "compensated" / "stochastic" (the "multiscatter" key).
MultiscatterMode read_multiscatter(const JsonObject& desc);

}  // namespace kozu
