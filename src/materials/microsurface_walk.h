// microsurface_walk: the multiple-scattering microfacet BSDF of the Smith microsurface, sampled and
// evaluated without bias by a random walk on the microsurface, for conductors and dielectrics, GGX or
// Beckmann, isotropic or anisotropic.
//
// Citation: Heitz, Hanika, d'Eon, Dachsbacher 2016, "Multiple-Scattering Microfacet BSDFs with the Smith
// Model" (ACM TOG 35(4), SIGGRAPH 2016), derived here from the paper's model; the
// blog posts of ushiostarfish 2018 (ushiostarfish's diary) name it as the ground truth of multiple scattering. The
// microfacet quantities D, Λ and the VNDF sampler come from microfacet.h.
//
// Equation map. The numbers below are this file's own (the "eq. (N)" tags on code lines point here);
// each names the part of the paper's model it implements.
//   (1) heights: uniform, P1(h) = 1/2 on [−1, 1], C1(h) = (1 + h)/2. The BSDF does not depend on the
//       choice (paper, "microsurface height distribution"); the walk stores c = C1(h).
//   (2) Λ of a downward direction: Λ(ω) = −1 − Λ(−ω) for ω.z < 0 (Λ of microfacet.h is that of |ω.z|).
//   (3) height-dependent masking: a ray leaving height h in direction ω (ω.z > 0) escapes the
//       microsurface with probability G1(ω, h) = C1(h)^Λ(ω).
//   (4) free-path (height) sampling: a ray at height h0 in direction ω meets no microfacet before height
//       h with probability (C1(h0) / C1(h))^Λ(ω) (signed Λ, both directions), so the next intersection is
//       at C1(h) = C1(h0) U^(−1/Λ(ω)); above C1 = 1 the ray has left. Downward rays always intersect.
//   (5) projected area of the microsurface seen from any ω: A(ω) = ∫ ⟨ω, m⟩⁺ D(m) dm
//       = cos θ (1 + Λ(ω)) with the signed Λ of (2), i.e. |cos θ| Λ(−ω) for ω.z < 0.
//   (6) visible normals from any ω: D_ω(m) = ⟨ω, m⟩⁺ D(m) / A(ω); sampled by
//       MicrofacetDistribution::sample_visible(ω), also for ω.z < 0 (tested in the test file).
//   (7) conductor phase function: p(ωa → ωb) = F(ωa·m) D_ωa(m) / (4 |ωa·m|), m = (ωa + ωb)/|ωa + ωb|;
//       ωa points back along the arriving ray, ωb along the leaving one.
//   (8) dielectric phase function, η = IOR beyond the facet / IOR on ωa's side: reflection as (7) with
//       the dielectric F; refraction (1 − F(ωa·m)) D_ωa(m) η² |ωb·m| / (ωa·m + η ωb·m)²,
//       m = ±(ωa + η ωb)/|…| oriented to m.z > 0 (Walter et al. 2007's Jacobian); choose by F.
//   (9) two-sided dielectric microsurface: the lower side is the same statistical surface seen with
//       h → −h, z → −z, so crossing it maps C1 → 1 − C1 and flips the direction's z.
//  (10) walk density: a walk started along −ωo exits in ωi with density p(ωi | ωo) = f*(ωo → ωi) |cos θi|
//       (the adjoint BSDF: the walk traces importance). Estimated by next-event estimation: at each
//       vertex k, T_k p(ωa_k → ωi) G1(ωi, h_k) (G1 of (3), on the far side for a refraction).
//  (11) single scattering, the expectation of the first vertex of (10) over the first height (closed form):
//       reflection F D(m) / (4 |cos θo| (1 + Λo + Λi)) (height-correlated G2, Heitz 2014);
//       refraction (1 − F) D(m) |ωo·m| |ωi·m| η² B(1 + Λo, 1 + Λi) / (|cos θo| (ωo·m + η ωi·m)²),
//       B the Beta function (Heitz 2014's height-correlated masking for transmission).
//  (12) reciprocity, path by path: p(ωi | ωo) = R p(ωo | ωi), R = |cos θi| / |cos θo| · (η_i / η_o)²
//       (η_i, η_o the IORs on ωi's and ωo's sides). Evaluation runs one walk from ωo (NEE towards ωi) and
//       one from ωi (NEE towards ωo, times R), and combines them with the balance heuristic; the ratio
//       of the two strategies' path densities is the ratio of the NEE values at the path's two ends:
//       w_fwd = R N_rev / (N_fwd + R N_rev), N_rev the reverse walk's NEE at the first vertex (with its
//       forced-intersection probability of (13) for the segment from vertex 2).
//  (13) forced intersection (a variance reduction of (10), not in the paper): the NEE for vertex k is made
//       from vertex k − 1 as P(hit) · NEE(h'), h' drawn from the intersection heights given a hit, with
//       P(hit) = 1 − G1(ω, h) for an upward ray (1 downward). Unbiased; it cancels the 1/Λ of D_ω for rays
//       travelling upwards (A(ω) ∝ Λ), which gives the plain estimator infinite variance.
//
// Parameters (constructor): the MicrofacetDistribution (type GGX/Beckmann, α_x, α_y ≥ 1e-3).
// Per call: the conductor Fresnel (perfect, or complex IOR eta + i k per RGB channel); the dielectric
// relative IOR eta = n_inside / n_outside (+z is outside; eta ≠ 1, eta > 0) and the TransportMode.
//
// Deviations and choices
//  - Single scattering is evaluated in closed form (11), the exact expectation of the walk's first
//    next-event term; the walk estimates orders ≥ 2 only. eval is therefore exact for set_max_order(1).
//  - Next-event estimates use the forced intersection of (13) instead of the walk's own vertex.
//  - Evaluation is bidirectional with MIS (12) for conductors as well as dielectrics (the paper combines
//    the two directions for the dielectric); set_bidirectional(false) gives the plain one-walk estimator
//    of (10), for tests and variance comparisons.
//  - Walks are cut after kMaxOrder = 256 scattering events and count as absorbed (sample returns false,
//    eval drops those orders). None of the ~12 million walks of test_microsurface_walk_stat reached it;
//    the worst cases measured (α = 1 conductor at normal incidence, α = 1 glass seen from inside) never
//    exceeded 15 bounces in 300k walks, and their tails decay geometrically by ≤ 0.45 per bounce, which
//    puts P(order > 256) below 1e-90.
//  - eta = 1 (an index-matched interface) makes refraction a Dirac delta: not supported.
#pragma once

#include "core/color.h"
#include "core/rng.h"
#include "materials/bsdf.h"
#include "materials/fresnel.h"
#include "materials/microfacet.h"

namespace kozu {

// A generator seeded from a BSDF call's arguments (two directions, or a direction and the sample's
// random numbers) and a per-model salt: the walk's estimate is then a deterministic function of the
// call, so renders stay reproducible, while differing between the continuous directions a renderer asks.
Pcg32 walk_rng(const Vec3& a, const Vec3& b, uint64_t salt);

class MicrosurfaceWalk {
 public:
  static constexpr int kMaxOrder = 256;

  explicit MicrosurfaceWalk(const MicrofacetDistribution& d) : d_(d) {}

  const MicrofacetDistribution& distribution() const { return d_; }

  // Conductor, two-sided (if wo.z < 0 both directions are mirrored to the upper side). An unbiased
  // estimate of f(wo, wi) |cos θi| including all scattering orders (up to max_order()).
  Rgb eval_conductor(const Vec3& wo, const Vec3& wi, const ConductorFresnel& F, Pcg32& rng) const;
  // Samples wi by the walk; *weight = f |cos θi| / pdf = the product of the per-bounce Fresnel terms.
  // Returns false when the walk did not exit within max_order() bounces. *order (optional) receives the
  // number of scattering events of the walk.
  bool sample_conductor(const Vec3& wo, const ConductorFresnel& F, Pcg32& rng, Vec3* wi, Rgb* weight,
                        int* order = nullptr) const;

  // Dielectric interface with eta = n_inside / n_outside (the +z side is outside); wo on either side.
  // Unbiased estimate of f(wo, wi) |cos θi| (reflection and transmission; Radiance mode includes
  // 1/eta_wi² per bsdf.h, eta_wi = IOR on wi's side / IOR on wo's side).
  float eval_dielectric(const Vec3& wo, const Vec3& wi, float eta, TransportMode mode, Pcg32& rng) const;
  // Samples wi by the walk (choosing reflection or refraction by Fresnel at every bounce); *weight is 1,
  // or 1/eta_wi² for a transmission in Radiance mode.
  bool sample_dielectric(const Vec3& wo, float eta, TransportMode mode, Pcg32& rng, Vec3* wi, float* weight,
                         int* order = nullptr) const;

  // Highest scattering order kept: 1 gives single scattering only. n <= 0 or n > kMaxOrder means
  // kMaxOrder (the default).
  void set_max_order(int n) { max_order_ = (n <= 0 || n > kMaxOrder) ? kMaxOrder : n; }
  int max_order() const { return max_order_; }
  // Bidirectional MIS evaluation (default) or the single forward walk of eq. (10).
  void set_bidirectional(bool on) { bidirectional_ = on; }
  bool bidirectional() const { return bidirectional_; }

 private:
  MicrofacetDistribution d_;
  int max_order_ = kMaxOrder;
  bool bidirectional_ = true;
};

}  // namespace kozu
