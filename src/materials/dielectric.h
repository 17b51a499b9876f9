// dielectric: an interface between the outside (the shading normal's side) and a medium of IOR `ior`,
// smooth (Dirac reflection and refraction) or rough (Walter et al. 2007 microfacet reflection and
// refraction), with optional multiple-scattering energy compensation. Correct from either side:
// from inside the relative IOR is 1/ior and total internal reflection occurs.
//
// Citations: Walter, Marschner, Li, Torrance 2007, "Microfacet Models for Refraction through Rough
// Surfaces" (eqs. 16, 20–21 for the generalized half vector, the BTDF and its Jacobian); Heitz 2014
// (height-correlated G2); Kulla & Conty 2017 via ushiostarfish 2018 (blog, ushiostarfish's diary) for the
// coupled compensation lobe; Heitz et al. 2016 for `stochastic`.
// Equation map (η = IOR on wi's side / IOR on wo's side; all cosines with respect to the macro normal):
//   reflection      f_r cos θi = F(ωo·h) D(h) G2 / (4 |cos θo|),  h = normalize(ωo + ωi)
//   refraction      f_t cos θi = (1 − F) D(h) G2 |ωi·h| |ωo·h| / (|cos θo| (ωi·h + ωo·h/η)²) / η² (Radiance)
//                   h = ±normalize(ωo + η ωi)                                      (Walter eq. 16, 21)
//   sampling        visible normals of ωo, then reflect with probability F, else refract
//   compensation    from side s (E_s = single-scattering reflect+transmit albedo from that side):
//                   f_ms cos θi = (1 − E_s(μo)) · { r_s (1 − E_s(μi)) / (π (1 − Ē_s))   same side
//                                                 { t_s (1 − E_s̄(μi)) / (π (1 − Ē_s̄))   other side (/η²)
//                   r_s + t_s = 1 (energy) and t_s̄ = t_s (1 − Ē_s) / (η_s² (1 − Ē_s̄)) (reciprocity of the
//                   transmitted part); t on the side facing the denser medium is the smooth interface's
//                   1 − F_avg, capped so the other side's t stays ≤ 1. Derivation: docs/materials.md.
//
// Parameters
//   ior           float   1.5    > 0   IOR of the inside relative to the outside
//   roughness/alpha/alpha_u+alpha_v/gloss, distribution, gloss_model: roughness.h; none = smooth;
//                 each may be a texture (then the interface is rough; compensation tables per 1/255 step)
//   multiscatter  string  "none" "none" | "compensated" | "stochastic"
//
// Deviation: an index-matched interface (|ior − 1| < kIndexMatchedTolerance) is smooth whatever its roughness:
// it does not scatter (every microfacet passes light straight through, a Dirac delta the rough lobes cannot
// represent), so kozu renders it exactly as the smooth interface (straight transmission) instead.
#pragma once

#include "materials/conductor.h"  // MultiscatterMode
#include "materials/material.h"
#include "materials/microfacet.h"
#include "materials/microfacet_albedo.h"
#include "materials/roughness.h"
#include "materials/roughness_tables.h"

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

// Per-material precomputation of the compensated mode, per side (0: outside, 1: inside).
struct DielectricCompensation {
  AlbedoCurve e[2];
  CoupledLobe lobe[2];
  float t[2] = {0, 0};  // share of the restored energy that is transmitted, per side
  // The tables of an interface of relative IOR ior (inside over outside) and roughness alpha.
  static DielectricCompensation make(MicrofacetType type, float alpha, float ior);
};

class RoughDielectricBsdf final : public JointBsdf {
 public:
  RoughDielectricBsdf(const MicrofacetDistribution& d, float eta, const DielectricCompensation* comp)
      : d_(d), eta_(eta), comp_(comp) {}
  BsdfSample sample(const Vec3& wo, float u_lobe, const Vec2& u, TransportMode mode) const override;
  Rgb eval_pdf(const Vec3& wo, const Vec3& wi, float* pdf_out, TransportMode mode) const override;
  uint32_t flags() const override { return kBsdfReflection | kBsdfTransmission | kBsdfGlossy; }

 private:
  MicrofacetDistribution d_;
  float eta_;
  const DielectricCompensation* comp_;  // null for "none"
};

// Heitz et al. 2016 random walk; pdf is a proxy for MIS weights only (see StochasticConductorBsdf).
class StochasticDielectricBsdf final : public Bsdf {
 public:
  StochasticDielectricBsdf(const MicrofacetDistribution& d, float eta) : d_(d), eta_(eta) {}
  Rgb eval(const Vec3& wo, const Vec3& wi, TransportMode mode) const override;
  BsdfSample sample(const Vec3& wo, float u_lobe, const Vec2& u, TransportMode mode) const override;
  float pdf(const Vec3& wo, const Vec3& wi) const override;
  uint32_t flags() const override { return kBsdfReflection | kBsdfTransmission | kBsdfGlossy; }

 private:
  MicrofacetDistribution d_;
  float eta_;
};

// Tolerance of "index-matched" (see the header).
inline constexpr float kIndexMatchedTolerance = 1e-3f;
inline bool index_matched(float ior) { return std::abs(ior - 1.0f) < kIndexMatchedTolerance; }

class DielectricMaterial final : public Material {
 public:
  DielectricMaterial(float ior, bool smooth, const MicrofacetDistribution& d = {},
                     MultiscatterMode mode = MultiscatterMode::None);
  // A dielectric with a textured roughness (roughness.h); rough unless index-matched.
  DielectricMaterial(float ior, std::unique_ptr<const TexturedRoughness> roughness, MultiscatterMode mode);
  static Deferred<Material> parse(const JsonObject& desc, const MaterialParseContext& ctx);
  const Bsdf* bsdf(const SurfaceInteraction& si, Arena& arena) const override;
  bool may_be_specular() const override { return smooth_; }  // index-matched ones too: they pass light straight on
  float ior() const { return ior_; }
  // The roughness at si: its distribution and, in the compensated mode, its tables (null otherwise). Not for a
  // smooth interface.
  MicrofacetDistribution distribution_at(const SurfaceInteraction& si, const DielectricCompensation** comp) const;
  // The RoughnessTables key of the roughness at si (subsurface.h keys its own tables on it); 0 when constant.
  float table_key_at(const SurfaceInteraction& si) const;
  // Textured roughness: the rough BSDF of a table key's level (subsurface.h integrates its transmittance).
  RoughDielectricBsdf level_bsdf(float key) const;
  bool smooth() const { return smooth_; }
  bool textured() const { return rough_tex_ != nullptr; }
  // Textured roughness: the table key of a constant one (nullopt when it varies).
  std::optional<float> constant_table_key() const { return rough_tex_->constant_key(); }

 private:
  float ior_;
  bool smooth_;
  MicrofacetDistribution d_;
  MultiscatterMode mode_;
  DielectricCompensation comp_;
  // Textured roughness: the distribution per hit, the compensation tables per level (null / unused otherwise).
  std::unique_ptr<const TexturedRoughness> rough_tex_;
  RoughnessTables<DielectricCompensation> tex_comp_;
};

}  // namespace kozu
