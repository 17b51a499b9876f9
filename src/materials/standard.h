// standard: the glTF 2.0 metallic-roughness material (the model real assets are authored in), with its clearcoat,
// sheen, specular and transmission extensions, made energy-conserving and reciprocal with kozu's compensation
// tables. Every parameter may be a texture.
//
// Citations: the Khronos glTF 2.0 specification, Appendix B (BRDF implementation: metal = conductor Fresnel with
// F0 = base colour, dielectric = a Fresnel-weighted mix of a specular coat over a diffuse base) and the extension
// specifications KHR_materials_clearcoat, _sheen, _specular, _transmission, _ior; Schlick 1994 (the metal's
// Fresnel); the coupled compensation of ushiostarfish 2018 (blog, ushiostarfish's diary; Kelemen & Szirmay-Kalos
// 2001; Kulla & Conty 2017), as in plastic.h and conductor.h; Chan 2018 ("Material Advances in Call of Duty: WWII")
// §5.8 eqs. (64)–(69) for `diffuse_model: cod-multiscatter`. Equation map (c = base colour, m = metallic, t =
// transmission, α = roughness², μ = |cos θ|, all f include cos θi):
//   f        = cc f_cc + C(ωo) C(ωi) [ f_sheen + S(ωo) S(ωi) f_base ]        layering by albedo scaling
//   C(ω)     = 1 − cc E_cc(μ)          S(ω) = 1 − max(sheen_color) E_sheen(μ)   (1 on the inside, see below)
//   f_base   = m f_metal + (1 − m) [ (1 − t) f_opaque + t f_glass ]         glTF's mix(dielectric, metal, m)
//   f_metal  = F_schlick(c, ωo·h) D G2 / (4 μo) + F_ms (1 − E(μo))(1 − E(μi)) μi / (π (1 − E_avg))
//              F_ms = F_avg² E_avg / (1 − F_avg (1 − E_avg)), F_avg = c + (1 − c)/21   (ushiostarfish 2018
//              "多重拡散項の近似"; F_avg is 2 ∫ F_schlick(μ) μ dμ in closed form)
//   f_opaque = s F(ωo·h, ior) D G2 / (4 μo) + c (1 − s E_R(μo))(1 − s E_R(μi)) μi / (π (1 − s E_R,avg))
//              s = specular × specular_color; with s = 1 this is plastic.h's Kelemen coupling (ushiostarfish 2018
//              f_matte)
//   f_glass  = the compensated rough dielectric of relative IOR ior (dielectric.h), transmission tinted by c
//   f_cc     = F(ωo·h, 1.5) D_cc G2_cc / (4 μo), α_cc = clearcoat_roughness²
//   f_sheen  = sheen_color × sheen.h's Charlie lobe
// E, E_R, E_cc come from microfacet_albedo.h's tables; E_sheen from sheen.h's.
// White furnace: with c = 1, s = 1, no coat and no sheen the albedo is 1 (to the tables' accuracy) for every m,
// t and α; the coat and the sheen only remove energy (C, S ≤ 1). Every term is symmetric in ωo and ωi (the glass
// term in dielectric.h's generalized sense), so f is reciprocal.
//
// Sides: an opaque surface (t = 0 at the hit) is two-sided like plastic; a transmissive one has an outside (the
// shading normal's side), and the clearcoat and sheen lie on it: C and S are 1 for directions inside, and f_cc and
// f_sheen need both directions outside. The opaque lobes stay two-sided under t > 0.
//
// Sampling: one lobe is chosen in proportion to its albedo estimate at ωo (clearcoat, sheen, metal single and
// multiple scattering, coat, base, glass), drawn by that lobe's sampler (visible normals; sheen.h's and the base's
// cosine lobes; CoupledLobe), and the sample carries the mixture's value and pdf (Bsdf::sample_at).
//
// Parameters (every number and rgb key also takes a texture, textures/texture_parse.h)
//   base_color           rgb    0.8   in [0, 1]
//   metallic             float  0     in [0, 1]
//   roughness            float  0.5   in [0, 1]  α = roughness²; α below 1e-3 renders at 1e-3 (no Dirac lobes)
//   ior                  float  1.5   in [1, 3]  (a number: the tables are built per material)
//   specular             float  1     in [0, 1]  KHR_materials_specular's factor
//   specular_color       rgb    1     in [0, 1]  tints the whole coat reflection (glTF tints F0 only)
//   transmission         float  0     in [0, 1]
//   clearcoat            float  0     in [0, 1]
//   clearcoat_roughness  float  0     in [0, 1]
//   sheen_color          rgb    0     in [0, 1]
//   sheen_roughness      float  0.3   in [0, 1]  clamped to ≥ 0.07 (sheen.h)
//   diffuse_model        string "lambert"  "lambert" or "cod-multiscatter": Chan 2018's multiple-scattering
//                        diffuse (cod_multiscatter_diffuse.h) at the gloss of α, summed with the coat's specular as
//                        the game ships it (not energy-conserving: see cod_multiscatter_diffuse.h)
//   cod_energy_split     bool   false  cod-multiscatter only: Chan 2018 §5.3's explicit energy conservation, the
//                        diffuse scaled by (1 − s E_R(μo))(1 − s E_R(μi)), the light the coat's specular leaves in both
//                        directions (its directional albedo E_R at μo and, by reciprocity, at μi, as the paper's
//                        second EnvBrdfLut fetch at n·l); not normalised, unlike lambert's coupling
// Deviations: glTF's transmission is thin-walled without KHR_materials_volume; kozu's refracts (the surface bounds
// a solid of IOR ior). Textured roughness is quantized to 1/255 (an 8-bit texture's own steps) so that the tables
// of each level are built once.
#pragma once

#include "materials/dielectric.h"
#include "materials/material.h"
#include "materials/microfacet.h"
#include "materials/microfacet_albedo.h"
#include "materials/roughness_tables.h"

#include <array>
#include <memory>

namespace kozu {

// The tables that depend on one roughness (and the material's ior).
struct StandardTables {
  float alpha = 0;
  AlbedoCurve metal_e;  // conductor E(μ), F = 1
  CoupledLobe metal_lobe;
  AlbedoCurve coat_e;  // dielectric coat reflection E_R(μ) at ior
  CoupledLobe coat_lobe;
  DielectricCompensation glass;  // built only when the material transmits
  float gloss = 0;               // cod-multiscatter: the WWII gloss of α
  static StandardTables make(float alpha, float ior, bool glass);
};

// The clearcoat's reflection albedo at one roughness (ior 1.5).
struct ClearcoatTables {
  float alpha = 0;
  AlbedoCurve e;
  static ClearcoatTables make(float alpha);
};

// CodMultiscatterSplit: the cod-multiscatter diffuse under Chan 2018 §5.3's explicit energy split (key
// cod_energy_split).
enum class StandardDiffuse { Lambert, CodMultiscatter, CodMultiscatterSplit };

// The material's values at one hit.
struct StandardPoint {
  Rgb base_color{0.8f};
  float metallic = 0;
  float alpha = 0.25f;
  Rgb specular{1.0f};  // specular × specular_color
  float transmission = 0;
  float clearcoat = 0;
  float clearcoat_alpha = 0;
  Rgb sheen_color{0.0f};
  float sheen_roughness = 0.3f;
};

class StandardBsdf final : public JointBsdf {
 public:
  StandardBsdf(const StandardPoint& p, float ior, StandardDiffuse diffuse, const StandardTables* tables,
               const ClearcoatTables* coat);
  BsdfSample sample(const Vec3& wo, float u_lobe, const Vec2& u, TransportMode mode) const override;
  Rgb eval_pdf(const Vec3& wo, const Vec3& wi, float* pdf_out, TransportMode mode) const override;
  uint32_t flags() const override;
  // Opaque points (transmission 0), seen from outside: the clearcoat and the dielectric specular lobe from the
  // specular table, the metal as the compensated conductor's (conductor.h; its single scattering weighted by
  // Schlick's F0 n + (1 − F0) n_F), each with its exact albedo (lights/ltc_table.h); the base as a clamped cosine
  // of its exact albedo c (1 − s E_R(μo)) (cod-multiscatter: its value towards the light, diffuse_ltc_lobe), sharing
  // one LTC with the metal's coupled lobe. Under a clearcoat or sheen the base lobes are scaled by C(ωo) S(ωo); the
  // sheen itself is left to the residual.
  int ltc_lobes(const Vec3& wo, const Vec3& toward, LtcLobe* out) const override;
  float narrowest_ltc_alpha() const override;

 private:
  enum Lobe { kCoat, kSheen, kMetal, kMetalMs, kSpecular, kBase, kGlass, kLobes };
  // Lobe-choice probabilities at wo (in the frame where an opaque surface's wo is outside).
  std::array<float, kLobes> lobe_weights(const Vec3& wo) const;
  // C(ω) S(ω) for a direction on the outside, 1 inside.
  float layer_transmittance(const Vec3& w) const;
  // The two-sided opaque part (metal, specular, base) for wo, wi on the same side, with its mixture pdf terms.
  Rgb eval_opaque(const Vec3& wo, const Vec3& wi, const std::array<float, kLobes>& w, float* pdf) const;
  bool flip(const Vec3& wo) const { return p_.transmission == 0.0f && wo.z < 0.0f; }

  StandardPoint p_;
  float ior_;
  StandardDiffuse diffuse_;
  const StandardTables* tables_;
  const ClearcoatTables* coat_;
  MicrofacetDistribution d_, d_coat_;
  float sheen_max_;
  float specular_mean_;
  Rgb f_ms_;  // the metal's multiple-scattering Fresnel F_ms
  RoughDielectricBsdf glass_;
};

class StandardMaterial final : public Material {
 public:
  struct Textures {
    std::unique_ptr<const Texture> base_color, metallic, roughness, specular, specular_color, transmission, clearcoat,
        clearcoat_roughness, sheen_color, sheen_roughness;
  };
  StandardMaterial(Textures textures, float ior, StandardDiffuse diffuse);
  static Deferred<Material> parse(const JsonObject& desc, const MaterialParseContext& ctx);
  const Bsdf* bsdf(const SurfaceInteraction& si, Arena& arena) const override;
  // The values at a lookup (tests and the BSDF).
  StandardPoint point(const TextureQuery& q) const;

 private:
  Textures tex_;
  float ior_;
  StandardDiffuse diffuse_;
  RoughnessTables<StandardTables> tables_;
  RoughnessTables<ClearcoatTables> coat_tables_;
};

}  // namespace kozu
