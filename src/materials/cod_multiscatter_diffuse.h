// cod-multiscatter (a `diffuse` model): Chan's hand-fitted approximation of the diffuse BRDF of a
// GGX microsurface whose facets are Lambertian under a diffuse Fresnel term, with multiple
// scattering between facets: it flattens rough surfaces (retro-reflection at grazing angles) and
// darkens smooth ones at grazing angles (energy lost to the specular layer).
//
// Citation: Danny Chan, "Material Advances in Call of Duty: WWII", SIGGRAPH 2018 course Advances in
// Real-Time Rendering, 2018: §1.1 (gloss) and §5.8 (eqs. 64–69).
//
// Equation map (l = wi, v = wo, n = +z, h = (l + v) / |l + v|, g = gloss)
//   g, the WWII gloss; alpha = sqrt(2 / (1 + 2^(18 g)))        eq. (2), via roughness.h
//   f0 = l·h + (1 − l·h)^5                 rough foundation    eq. (64)
//   f1 = (1 − 0.75 (1 − n·l)^5)(1 − 0.75 (1 − n·v)^5)  smooth  eq. (65)
//   t  = clamp(2.2 g − 0.5, 0, 1)                              eq. (66)
//   fd = f0 + (f1 − f0) t                                      eq. (67)
//   fb = (34.5 g² − 59 g + 24.5)(l·h) 2^(−max(73.2 g − 21.2, 8.9) sqrt(n·h))  grazing bump  eq. (68)
//   fr = rho / pi (fd + fb)                                    eq. (69)
// l·h = v·h and every other term is symmetric in l and v, so fr is reciprocal.
//
// Parameters
//   albedo  rgb    0.5  each in [0, 1]  rho
//   gloss   float  0.5  in [0, 1]       g; `roughness` / `alpha` / `alpha_u`+`alpha_v` are mapped to g
//                                       by inverting eq. (2) (roughness.h)
//
// Deviations from the paper
//   - fd + fb is clamped at 0. The bump's coefficient 34.5 g² − 59 g + 24.5 = 34.5 (g − 1)(g − 0.7101)
//     is negative for g in (0.7101, 1), and where l and v both lie within about half a degree of the
//     horizon (n·h < 0.0075) the negative bump outweighs fd (there f1 -> 1/16): unclamped, fd + fb
//     reaches −0.66 at g = 0.85. The clamp changes the directional albedo by < 3e-6 (measured at
//     mu_o = 0.001 for g in [0.75, 0.95]).
//   - Two-sided like lambert: n·l and n·v are |cos theta|, h is taken on wo's side.
//   - As in the paper, the BRDF does not conserve energy for every gloss: with rho = 1 and g = 0 the
//     directional albedo exceeds 1 at grazing view (1.158 at mu_o = 0); docs/materials.md
//     tabulates it.
// Sampled with the cosine-weighted hemisphere, pdf = |cos theta_i| / pi (diffuse.h).
#pragma once

#include "materials/diffuse.h"

namespace kozu {

class CodMultiscatterDiffuseBsdf final : public Bsdf {
 public:
  CodMultiscatterDiffuseBsdf(const Rgb& albedo, float gloss);
  Rgb eval(const Vec3& wo, const Vec3& wi, TransportMode mode) const override;
  BsdfSample sample(const Vec3& wo, float u_lobe, const Vec2& u, TransportMode mode) const override;
  float pdf(const Vec3& wo, const Vec3& wi) const override;
  Rgb eval_pdf(const Vec3& wo, const Vec3& wi, float* pdf_out, TransportMode mode) const override;
  uint32_t flags() const override { return kBsdfReflection | kBsdfDiffuse; }
  // A clamped cosine weighted by the model's value towards the light (diffuse_ltc_lobe).
  int ltc_lobes(const Vec3& wo, const Vec3& toward, LtcLobe* out) const override {
    return diffuse_ltc_lobe(*this, wo, toward, out);
  }

  // max(fd + fb, 0) = pi fr / rho, for wo and wi in the same hemisphere.
  float shape(const Vec3& wo, const Vec3& wi) const;

 private:
  Rgb albedo_;
  float t_;           // eq. (66)
  float bump_scale_;  // 34.5 g² − 59 g + 24.5, eq. (68)
  float bump_rate_;   // max(73.2 g − 21.2, 8.9), eq. (68)
};

}  // namespace kozu
