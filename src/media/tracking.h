// Distance sampling and transmittance estimation in a medium, against the medium's majorants.
//
//  sample_free_flight  spectral tracking (Kutz, Habel, Li, Novák 2017, "Spectral and Decomposition Tracking
//                      for Rendering Heterogeneous Volumes"): delta tracking with one majorant for all
//                      channels; at each tentative collision a real scattering or a null event is chosen with
//                      probabilities proportional to the throughput-weighted coefficients, and beta takes the
//                      ratio σ_x / (σ̄ P_x) per channel. Absorption is never sampled: it lowers the weights.
//                      Unbiased for any positive event probabilities, and exact for spectrally varying media.
//  ratio_tracking      Cramer 1978 / Novák, Selle, Jarosz 2014: T = Π (1 − σt/σ̄) over the tentative
//                      collisions, per channel, with Russian roulette once every channel is below 0.1.
// σt may depend on the direction (microflake media): both evaluate it along the ray's direction.
// Media with levels of detail per lookup (Medium::level_for): the ray is split where its cone's width leaves the
// range a level serves, and each part is tracked against that level's own majorants and coefficients.
// Both take one step of the path's budget per tentative collision (core/path_budget.h); when it runs out the
// flight ends absorbed (beta = 0, false) and the transmittance is 0.
#pragma once

#include "core/path_budget.h"
#include "core/rng.h"
#include "geometry/ray.h"
#include "geometry/ray_cone.h"
#include "media/medium.h"

namespace kozu {

// The uniform numbers a walk draws: the first ones given (the sampler's stratified dimensions: the first
// tentative collision and the first event decide most flights where the majorants are tight, so stratifying them
// across a pixel's samples does what it does for a homogeneous medium's closed-form flight), the rest from rng.
class WalkUniforms {
 public:
  explicit WalkUniforms(Pcg32& rng) : rng_(rng) {}
  WalkUniforms(Pcg32& rng, Vec2 first) : rng_(rng), first_{first.x, first.y}, given_(2) {}
  float next() { return used_ < given_ ? first_[used_++] : rng_.next_float(); }

 private:
  Pcg32& rng_;
  float first_[2] = {0.0f, 0.0f};
  int given_ = 0, used_ = 0;
};

// Samples a real scattering event along ray in [0, t_max); true with *t_out there. beta is updated either way
// (a path that reaches t_max carries the weights of its null events).
bool sample_free_flight(const Medium& medium, const Ray& ray, float t_max, WalkUniforms u, Rgb& beta, float* t_out,
                        PathBudget& budget, const RayCone& cone = {});
inline bool sample_free_flight(const Medium& medium, const Ray& ray, float t_max, Pcg32& rng, Rgb& beta, float* t_out,
                               PathBudget& budget, const RayCone& cone = {}) {
  return sample_free_flight(medium, ray, t_max, WalkUniforms(rng), beta, t_out, budget, cone);
}
// Unbiased per-channel estimate of the transmittance along ray over [0, t_max].
Rgb ratio_tracking(const Medium& medium, const Ray& ray, float t_max, WalkUniforms u, PathBudget& budget,
                   const RayCone& cone = {});
inline Rgb ratio_tracking(const Medium& medium, const Ray& ray, float t_max, Pcg32& rng, PathBudget& budget,
                          const RayCone& cone = {}) {
  return ratio_tracking(medium, ray, t_max, WalkUniforms(rng), budget, cone);
}

}  // namespace kozu
