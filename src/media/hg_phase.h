// hg_phase: the Henyey–Greenstein phase function (Henyey & Greenstein 1941); g = 0 is isotropic.
//
//   f_p(wo, wi) = (1 − g²) / (4π (1 + g² + 2g cos θ)^{3/2}),  cos θ = wo · wi
// (wo points back along the incoming path, so g > 0 favours wi = −wo: forward scattering.) Sampled exactly
// by inverting its cdf in cos θ (pbrt-v3 §15.2.3 form), so pdf = f = f_p and weight = 1.
//
// Parameters: g  float  0  in (−1, 1)  mean cosine of the scattering angle
#pragma once

#include "media/phase.h"

namespace kozu {

class HgPhase final : public PhaseFunction {
 public:
  explicit HgPhase(float g = 0.0f) : g_(g) {}
  float eval(const Vec3& wo, const Vec3& wi, Pcg32&) const override { return pdf(wo, wi); }
  PhaseSample sample(const Vec3& wo, const Vec2& u, Pcg32&) const override;
  float pdf(const Vec3& wo, const Vec3& wi) const override;
  float g() const { return g_; }

 private:
  float g_;
};

}  // namespace kozu
