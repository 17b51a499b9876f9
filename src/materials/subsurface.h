// subsurface: a translucent object seen through a dielectric boundary, with light transport inside
// summarised by the Christensen–Burley normalized-diffusion BSSRDF.
//
// Citation: Christensen & Burley 2015 (seed ../shared/seeds/001_87980b3445e6c614.txt).
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
// Parameters
//   albedo            rgb    0.8            each in [0, 1]  surface albedo A (multiple-scattering albedo)
//   mfp | dmfp        rgb    -              > 0             ℓ: volume mean free path, or diffuse mfp ℓd
//                                                           on the surface (exactly one; scene units)
//   parameterization  string "searchlight"  "searchlight" (eq. 5) | "diffuse" (eq. 6) need mfp;
//                            ("dmfp" when   "dmfp" (eq. 8) needs dmfp
//                            dmfp is given)
//   ior               float  1.4            > 0             boundary IOR
//   roughness/alpha/alpha_u+alpha_v/gloss, distribution: roughness.h (none = smooth boundary)
//   multiscatter      string "compensated"  "none" | "compensated"  (rough boundary only)
#pragma once

#include "bssrdf/probe_sampling.h"
#include "materials/dielectric.h"
#include "materials/microfacet_albedo.h"

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
  static Deferred<Material> parse(const JsonObject& desc, const MaterialParseContext& ctx);

  const Bsdf* bsdf(const SurfaceInteraction& si, Arena& arena) const override;
  const RgbProfile* subsurface_profile() const override { return &profile_; }
  // Sw at the second point of the BSSRDF.
  const Bsdf* subsurface_exit_bsdf(Arena& arena) const override {
    return arena.make<SubsurfaceExitBsdf>(&transmittance_);
  }
  // T(μ), the boundary's directional transmittance from outside, and c_T = transmittance().average().
  const AlbedoCurve& transmittance() const { return transmittance_; }

 private:
  DielectricMaterial boundary_;
  RgbProfile profile_;
  AlbedoCurve transmittance_;
};

}  // namespace kozu
