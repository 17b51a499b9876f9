// shirley (a `diffuse` model): the diffuse term of Shirley et al.'s smooth-coated matte surface, as
// corrected by Chan: light is reflected diffusely with the share the smooth coat (normal-incidence
// Fresnel reflectance F0) transmits both on the way in and on the way out.
//
// Citation: Danny Chan, "Material Advances in Call of Duty: WWII", SIGGRAPH 2018 course Advances in
// Real-Time Rendering, §5.4, correcting eq. (4) of P. Shirley, H. Hu, B. Smits, E. Lafortune, "A
// Practitioners' Assessment of Light Reflection Models", Pacific Graphics 1997.
// Equations: Chan 2018 §5.4 (eqs. 61–62).
//
// Equation map (l = wi, v = wo, n = +z)
//   k   = 21 / (20 pi) (1 − F0)                                     eq. (61)
//   F_d = k (1 − (1 − n·l)^5)(1 − (1 − n·v)^5)                       eq. (62)
//   f   = rho F_d   (eq. 62 already holds the 1/pi, so no further 1/pi)
//
// Directional albedo, in closed form (the point of eq. (61)'s 21/20 constant):
//   A(mu_o) = integral over the hemisphere of f cos theta_i
//           = rho k (1 − (1 − mu_o)^5) 2 pi integral_0^1 (1 − (1 − mu)^5) mu dmu
//   with integral_0^1 mu dmu = 1/2 and integral_0^1 (1 − mu)^5 mu dmu = B(2, 6) = 1! 5! / 7! = 1/42:
//           integral_0^1 (1 − (1 − mu)^5) mu dmu = 1/2 − 1/42 = 10/21, so
//   A(mu_o) = rho 21/(20 pi) (1 − F0) 2 pi 10/21 (1 − (1 − mu_o)^5) = rho (1 − F0)(1 − (1 − mu_o)^5).
//   At normal view all the light the coat lets in is returned: A(1) = rho (1 − F0).
//
// Parameters
//   albedo  rgb    0.5   each in [0, 1]  rho
//   f0      float  0.04  in [0, 1]       F0, the coat's normal-incidence reflectance (0.04: IOR 1.5)
//
// Deviations: two-sided like lambert (n·l and n·v are |cos theta|); only the diffuse term, the coat's
// specular reflection is not part of this BSDF.
// Sampled with the cosine-weighted hemisphere, pdf = |cos theta_i| / pi (diffuse.h).
#pragma once

#include "materials/diffuse.h"

namespace kozu {

class ShirleyDiffuseBsdf final : public Bsdf {
 public:
  ShirleyDiffuseBsdf(const Rgb& albedo, float f0);
  Rgb eval(const Vec3& wo, const Vec3& wi, TransportMode mode) const override;
  BsdfSample sample(const Vec3& wo, float u_lobe, const Vec2& u, TransportMode mode) const override;
  float pdf(const Vec3& wo, const Vec3& wi) const override;
  Rgb eval_pdf(const Vec3& wo, const Vec3& wi, float* pdf_out, TransportMode mode) const override;
  uint32_t flags() const override { return kBsdfReflection | kBsdfDiffuse; }
  // A clamped cosine weighted by the model's value towards the light (diffuse_ltc_lobe).
  int ltc_lobes(const Vec3& wo, const Vec3& toward, LtcLobe* out) const override {
    return diffuse_ltc_lobe(*this, wo, toward, out);
  }

  // The closed-form directional albedo above, rho (1 − F0)(1 − (1 − |cos theta_o|)^5).
  Rgb directional_albedo(const Vec3& wo) const;

 private:
  Rgb albedo_;
  float one_minus_f0_;
  Rgb scale_;  // rho k, eq. (61)
};

}  // namespace kozu
