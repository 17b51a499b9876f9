// homogeneous_flight: free flights through a homogeneous medium with densities in closed form, so that the path
// tracer can weigh them by MIS against another distance sampler (equiangular sampling towards a light,
// media/equiangular.h; integrators/path.cpp).
//
// Chromatic media take spectral MIS (Wilkie et al. 2014, "Hero Wavelength Spectral Sampling", §4, with three
// channels): a channel c is chosen with probability q_c ∝ β_c (the path's throughput, so that a channel it no longer
// carries is never chosen), the distance drawn from σt_c exp(−σt_c t), and every channel is weighted by the mixture
// density, the one-sample balance heuristic over the three:
//   p(t)    = Σ_c q_c σt_c exp(−σt_c t)        scattering at t < t_max, weight σs T(t) / p(t)
//   P(pass) = Σ_c q_c exp(−σt_c t_max)         no event before t_max,  weight T(t_max) / P(pass)
// with T(t) = exp(−σt t) per channel. For a grey medium the weights are the albedo and 1: plain exponential flights.
// Unbiased whatever q is, as long as q_c > 0 wherever β_c σs_c > 0.
#pragma once

#include "core/color.h"

namespace kozu {

// exp(−σt t) per channel, 1 where σt is 0 for any t (t may be infinite): the closed form that shadow rays take in place
// of ratio tracking's estimate.
Rgb homogeneous_transmittance(const Rgb& sigma_t, float t);

class HomogeneousFlight {
 public:
  HomogeneousFlight(const Rgb& sigma_t, const Rgb& beta);
  // A distance from two uniform numbers (channel, distance); infinite when the channel has σt 0.
  float sample(float u_channel, float u) const;
  // The density of scattering at t (per unit length).
  float pdf(float t) const { return pdf_of(transmittance(t)); }
  // The probability that a flight passes t_max (t_max may be infinite).
  float pass_probability(float t_max) const { return pass_probability_of(transmittance(t_max)); }
  // The same from the transmittance T = transmittance(t), for callers that need T too (one exp per channel, not two).
  float pdf_of(const Rgb& T) const;
  float pass_probability_of(const Rgb& T) const;
  // exp(−σt t) per channel (1 where σt is 0, for any t).
  Rgb transmittance(float t) const { return homogeneous_transmittance(sigma_t_, t); }

 private:
  Rgb sigma_t_;
  Rgb q_;
};

}  // namespace kozu
