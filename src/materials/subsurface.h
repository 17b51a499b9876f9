// subsurface: a translucent object seen through a dielectric boundary, with light transport inside
// summarised by the Christensen–Burley normalized-diffusion BSSRDF.
//
// Citation: Christensen & Burley 2015, "Approximate Reflectance Profiles for Efficient Subsurface
// Scattering", Pixar Technical Memo #15-04.
//   S(xi, ωi; xo, ωo) = C Ft(xi, ωi) R(|xo − xi|) Ft(xo, ωo)                     eq. (1)
//   R per color channel                                                          eq. (3), normalized_diffusion.h
// kozu's separable form, with T(μ) the boundary's directional transmittance from outside:
//   at the point where the camera path enters:   the boundary BSDF, sampled; a transmitted sample
//                                                carries weight T(μo) in expectation (η² factors of
//                                                entering and leaving cancel and are left out)
//   spatial part:                                R(r), sampled by probe rays (bssrdf/probe_sampling.h)
//   at the point where light leaves toward the path's next vertex:
//                                                Sw(ωi) |cos θi| = T(μi) |cos θi| / (π c_T),
//                                                c_T = 2 ∫ T(μ) μ dμ, so ∫ Sw |cos| dω = 1.
// So C = 1/(π c_T) and Ft = T: S = T(μi) R(r) T(μo) / (π c_T), symmetric in the two ends (reciprocal),
// and with albedo 1 every unit of energy the boundary transmits comes back out (energy conserving;
// the probe truncation loses 1e-5 of it). The smooth boundary's T is 1 − F (the dielectric Fresnel
// factor); a rough boundary's T is tabulated per material at 32 cosines by integrating its BSDF.
// Without multiple-scattering compensation a rough boundary loses energy as a rough dielectric does,
// so "compensated" is the default here.
//
// Textures: albedo, mfp/dmfp and the roughness keys take textures. The profile R is taken where the camera path
// enters (the albedo and mfp there, as Christensen–Burley renderers do: one profile per entry point, not a blend of
// the values around it), built per hit in the arena when albedo or mfp is textured. The exit BSDF Sw uses the
// transmittance T of the roughness where light leaves (tables per 1/255 step of a textured roughness,
// roughness_tables.h); Sw integrates to 1 for any T, so energy is conserved either way. With alpha_u/alpha_v
// textured, T is integrated for the isotropic RMS α (a plain anisotropic roughness integrates the anisotropic BSDF).
//
// Parameters (* = also takes a texture, textures/texture_parse.h; values clamped to the key's range)
//   albedo*           rgb    0.8            each in [0, 1]  surface albedo A (multiple-scattering albedo)
//   mfp* | dmfp*      rgb    -              > 0             ℓ: volume mean free path, or diffuse mfp ℓd
//                                                           on the surface (exactly one; scene units); a texture
//                                                           is read as data (no colour decoding), clamped ≥ 1e-6
//   parameterization  string "searchlight"  "searchlight" (eq. 5) | "diffuse" (eq. 6) need mfp;
//                            ("dmfp" when   "dmfp" (eq. 8) needs dmfp
//                            dmfp is given)
//   ior               float  1.4            > 0             boundary IOR
//   roughness*/alpha*/alpha_u*+alpha_v*/gloss*, distribution: roughness.h (none = smooth boundary; a texture =
//                                                           rough boundary)
//   multiscatter      string "compensated"  "none" | "compensated"  (rough boundary only)
#pragma once

#include "bssrdf/probe_sampling.h"
#include "materials/dielectric.h"
#include "materials/microfacet_albedo.h"
#include "materials/roughness.h"
#include "materials/roughness_tables.h"

namespace kozu {

// The boundary seen from the camera side: eval and pdf are the dielectric's reflection only (light
// never reaches xo through the interface directly: that path is the BSSRDF's); sample draws from the
// whole dielectric and a transmitted sample, flagged kBsdfTransmission, tells the integrator to
// continue through the BSSRDF. Its weight is the transmitted energy fraction (Importance mode).
class SubsurfaceBoundaryBsdf final : public JointBsdf {
 public:
  explicit SubsurfaceBoundaryBsdf(const Bsdf* dielectric) : inner_(dielectric) {}
  BsdfSample sample(const Vec3& wo, float u_lobe, const Vec2& u, TransportMode mode) const override;
  Rgb eval_pdf(const Vec3& wo, const Vec3& wi, float* pdf_out, TransportMode mode) const override;
  uint32_t flags() const override { return inner_->flags(); }

 private:
  const Bsdf* inner_;
};

// Sw at the point where light leaves the object, on the +z side, whatever wo is: T(μi)/(π c_T) |cos θi|,
// sampled by the cosine-weighted hemisphere.
class SubsurfaceExitBsdf final : public Bsdf {
 public:
  explicit SubsurfaceExitBsdf(const AlbedoCurve* transmittance) : t_(transmittance) {}
  Rgb eval(const Vec3& wo, const Vec3& wi, TransportMode mode) const override;
  BsdfSample sample(const Vec3& wo, float u_lobe, const Vec2& u, TransportMode mode) const override;
  float pdf(const Vec3& wo, const Vec3& wi) const override;
  uint32_t flags() const override { return kBsdfReflection | kBsdfDiffuse; }

 private:
  const AlbedoCurve* t_;
};

class SubsurfaceMaterial final : public Material {
 public:
  SubsurfaceMaterial(const Rgb& albedo, const Rgb& length, SubsurfaceParameterization p, float ior, bool smooth,
                     const MicrofacetDistribution& d = {}, MultiscatterMode mode = MultiscatterMode::Compensated);
  // Keys given as textures (null: the plain value).
  struct Textures {
    std::unique_ptr<const Texture> albedo, length;
    std::unique_ptr<const TexturedRoughness> roughness;  // with it the boundary is rough (smooth and d unused)
  };
  SubsurfaceMaterial(const Rgb& albedo, const Rgb& length, SubsurfaceParameterization p, float ior, bool smooth,
                     const MicrofacetDistribution& d, MultiscatterMode mode, Textures textures);
  static Deferred<Material> parse(const JsonObject& desc, const MaterialParseContext& ctx);

  const Bsdf* bsdf(const SurfaceInteraction& si, Arena& arena) const override;
  // R at the entry point si (see the header).
  const RgbProfile* subsurface_profile(const SurfaceInteraction& si, Arena& arena) const override;
  // Sw at the second point of the BSSRDF, si.
  const Bsdf* subsurface_exit_bsdf(const SurfaceInteraction& si, Arena& arena) const override {
    return arena.make<SubsurfaceExitBsdf>(&transmittance(si));
  }
  bool has_subsurface() const override { return true; }
  // T(μ), the boundary's directional transmittance from outside at si, and c_T = transmittance(si).average().
  const AlbedoCurve& transmittance(const SurfaceInteraction& si = {}) const;

 private:
  SubsurfaceParameterization param_;
  std::unique_ptr<const Texture> albedo_tex_, length_tex_;
  Rgb albedo_, length_;
  std::unique_ptr<const DielectricMaterial> boundary_;
  bool rough_textured_;
  RgbProfile profile_;
  AlbedoCurve transmittance_;                       // constant roughness
  RoughnessTables<AlbedoCurve> tex_transmittance_;  // textured roughness: T per level
};

}  // namespace kozu
