// lambertian_microsurface: the multiple-scattering BRDF of a GGX (or Beckmann) microsurface whose facets are
// Lambertian, optionally under the diffuse Fresnel term of Chan 2018 eq. (62), estimated without bias by a
// random walk on the microsurface. It is the reference that the hand fit of the `cod-multiscatter` diffuse
// (cod_multiscatter_diffuse.h, Chan 2018 eqs. (64)–(69)) approximates.
//
// Citation: D. Chan, "Material Advances in Call of Duty: WWII", SIGGRAPH 2018 course Advances in Real-Time
// Rendering in Games, §5.4–§5.6 (eqs. (61), (62); the slice parameterisation θ_h, θ_d at φ_d = 90°); the walk is
// that of Heitz, Hanika, d'Eon, Dachsbacher 2016, "Multiple-Scattering Microfacet BSDFs with the Smith Model",
// with the Lambertian-facet ("diffuse") phase function of that paper; heights, masking and free paths as in
// microsurface_walk.h, whose eq. numbers (1)–(6) the code cites as "walk eq. (N)".
//
// Equation map
//   Lambertian facet phase function p(ωa → ωb) = ∫ D_ωa(m) ρ W(ωa, ωb, m) ⟨ωb, m⟩⁺ / π dm   (Heitz 2016 §6)
//   diffuse Fresnel per bounce: ρ W / π with W = π k (1 − (1 − ωa·m)^5)(1 − (1 − ωb·m)^5),
//     k = 21 / (20π) (1 − F0)                                                       Chan 2018 eqs. (61), (62)
//     (the n of eq. (62) is the facet normal m: the term acts at every bounce, §5.4), W ≡ 1 without it
//   next-event estimate at each vertex: T ρ W ⟨ωi, m⟩⁺ / π · G1(ωi, h), m ~ D_ωa  (walk eqs. (3), (6), (10))
//   slice: h = (sin θ_h, 0, cos θ_h), l, v = (cos θ_d sin θ_h, ±sin θ_d, cos θ_d cos θ_h)  Chan 2018 §5.6, φ_d = 90°
//
// Parameters: the MicrofacetDistribution (α ≥ 1e-3); ρ, the facet albedo in [0, 1] (§5.4 uses 1: "our
// simulation always bounces 100% of the light"); the diffuse Fresnel on or off and its F0 in [0, 1) (0.04, §5.3).
//
// Deviations and choices
//  - The visible normal m drawn for a vertex serves both its next-event estimate and its continuation (the
//    estimate stays unbiased, the two are correlated). Each next-event term is bounded by ρ/π · 21/20, so the
//    estimator needs none of the forced intersections of microsurface_walk (its eq. (13)): there the 1/Λ of
//    D_ω came from evaluating a density, here m is sampled.
//  - One-sided: wo and wi in the upper hemisphere (the slice never leaves it); otherwise eval returns 0.
//  - Walks are cut after kMaxOrder = 256 bounces (energy dropped). With ρ = 1, W ≡ 1 and α = 1 the mean order
//    is 2.0 at normal incidence and 1.8 at θo = 80° (α = 0.3: 1.2), the largest 29 in 10⁶ walks (measured
//    with eval's *order); the white furnace of test_lambertian_microsurface would fail if the cut mattered.
#pragma once

#include "core/rng.h"
#include "materials/microfacet.h"

namespace kozu {

struct LambertianMicrosurfaceParams {
  float albedo = 1.0f;           // ρ of each facet
  bool diffuse_fresnel = false;  // Chan 2018 eq. (62) at every bounce
  float f0 = 0.04f;              // F0 of eq. (61)
};

class LambertianMicrosurface {
 public:
  static constexpr int kMaxOrder = 256;

  LambertianMicrosurface(const MicrofacetDistribution& d, const LambertianMicrosurfaceParams& p) : d_(d), p_(p) {}

  // One unbiased estimate of f(wo, wi) |cos θi| (all orders), from one walk started along −wo. Reciprocal
  // in expectation: the facet BRDF and W are symmetric. *order (optional): bounces of the walk.
  double eval(const Vec3& wo, const Vec3& wi, Pcg32& rng, int* order = nullptr) const;

  // Mean of n estimates of f(wo, wi) (the BRDF, without the cosine) and its standard error.
  double eval_mean(const Vec3& wo, const Vec3& wi, int n, Pcg32& rng, double* std_error = nullptr) const;

  // The slice directions of Chan 2018 §5.6 for θ_h, θ_d (radians), φ_d = 90°: l and v (z up).
  static void slice_directions(double theta_h, double theta_d, Vec3* l, Vec3* v);

 private:
  // π k (1 − (1 − a·m)^5)(1 − (1 − b·m)^5) of eqs. (61)–(62), or 1.
  double fresnel_weight(double am, double bm) const;

  MicrofacetDistribution d_;
  LambertianMicrosurfaceParams p_;
};

}  // namespace kozu
