// Light sampling shaped by a glossy BSDF lobe: a point on a flat area light drawn from the BSDF's narrowest LTC lobe
// restricted to the light (lights/ltc_polygon_sampler.h) with probability q, by the light's own sample() otherwise.
// One-sample MIS over the two (Veach 1997 §9.2.4): the density is the mixture's,
//   p(ω) = q p_lobe(ω) + (1 − q) p_light(ω),
// exact for both strategies, so the estimate stays unbiased whatever the lobe's fit; the BSDF's own sampling is
// weighed against this density by the power heuristic as against any light sample.
//
// Why: a quad light seen in a glossy surface (GGX α 0.02) is a highlight in which sampling the light by area puts
// most points outside the lobe and BSDF sampling misses the light's edges; the lobe restricted to the light draws
// directions close to the proportion of f cos over the light (up to the LTC fit, Heitz et al. 2016 eq. 1), so within
// the highlight f L / p is nearly constant.
//
// q is the lobe's share of the light the BSDF's lobes take from the polygon P: w_g ∫_P D_g over that plus the other
// lobes' weights times the clamped cosine's ∫_P D_o (eq. 3), each integral estimated from the light's solid angle
// (in D_g's cosine configuration through eq. 1's Jacobian) and the cosine at its triangles' centres rather than by
// eq. 11, which costs more than the sampler; capped at kMaxFraction so that the light's own sampling still covers
// what the fit misses (its tails, the lobe's horizon).
//
// Citations: Heitz, Dupuy, Hill, Neubelt 2016, "Real-Time Polygonal-Light Shading with Linearly Transformed
// Cosines", eqs. (1), (3); Veach 1997, "Robust Monte Carlo Methods for Light Transport Simulation", §9.2.4.
#pragma once

#include "core/frame.h"
#include "core/ltc.h"
#include "lights/area.h"
#include "lights/ltc_polygon_sampler.h"
#include "materials/bsdf.h"

#include <optional>
#include <span>

namespace kozu {

class LobeLightSampler {
 public:
  // A lobe more concentrated than this (|M⁻¹|: the clamped cosine's 1; for the GGX conductor's fits, 3.1 at α 0.32
  // seen from 24°; seen at grazing angles over docs/lights.md's floors, 95 at α 0.04, 9.5 at α 0.09, 4.0 at α 0.14,
  // 4.1 at α 0.2) shapes light samples. Broader ones gain too little for the sampler's cost.
  static constexpr float kMinConcentration = 4.0f;
  // Only BSDFs whose narrowest lobe is this smooth or smoother (Bsdf::narrowest_ltc_alpha; α = roughness²) are asked
  // for their lobes: asking costs (the rough floor, α 0.2, whose lobes barely pass kMinConcentration at grazing views,
  // took 14 % longer for 13 % less variance), and α 0.14 still gained 1.85× in efficiency (docs/lights.md).
  static constexpr float kMaxAlpha = 0.17f;
  // The most of the light samples the lobe takes.
  static constexpr float kMaxFraction = 0.8f;
  // Below this share the lobe is not used.
  static constexpr float kMinFraction = 0.05f;

  // frame and p: the vertex's shading frame and position; lobes: its BSDF's LTC lobes in that frame
  // (Bsdf::ltc_lobes); light: the light chosen there. valid() is false where the lobe does not take part: no narrow
  // lobe, a light that is not flat or does not face p, a lobe that does not see it.
  LobeLightSampler(const Frame& frame, const Vec3& p, std::span<const LtcLobe> lobes, const DiffuseAreaLight& light);
  LobeLightSampler(const LobeLightSampler&) = delete;
  LobeLightSampler& operator=(const LobeLightSampler&) = delete;

  bool valid() const { return q_ > 0.0f; }
  // q, the share of the samples drawn from the lobe.
  float fraction() const { return q_; }
  // A light sample from the mixture (valid() only); its pdf is the mixture's. Invalid where the lobe's direction
  // misses the light by rounding at its edge.
  LightSample sample(const LightSampleContext& ctx, const Vec2& u) const;
  // The mixture's density of the unit world direction wi towards a point of the light, given the light's own
  // density there.
  float pdf(const Vec3& wi, float light_pdf) const;

 private:
  const Frame frame_;
  const DiffuseAreaLight* light_;
  Ltc lobe_;
  std::optional<LtcPolygonSampler> sampler_;
  float q_ = 0.0f;
};

}  // namespace kozu
