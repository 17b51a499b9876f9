// The phase-function interface and its direction convention (the volumetric twin of bsdf.h).
//
// Conventions:
//  - Directions are unit vectors in world space.
//  - `wo` is given: it points from the scattering point towards the previous path vertex (the camera
//    side). `wi` is sampled: it points towards the next vertex (the light side). Both point away from
//    the scattering point, as in Heitz et al. 2015 ("The SGGX Microflake Distribution"), whose f_p(ωi → ωo) with ωi =
//    our wo.
//  - `eval(wo, wi)` is f_p per unit solid angle of wi; ∫ f_p dwi = 1 (eq. 7). No cosine.
//  - `pdf(wo, wi)` is a density per unit solid angle of wi.
//  - Reciprocity (eq. 8): σ(wo) f_p(wo, wi) = σ(wi) f_p(wi, wo), with σ the medium's projected area
//    (1 for isotropic media, which makes f_p symmetric).
//  - Stochastic phase functions (the SGGX diffuse phase, eq. 26) take a generator: eval is then an
//    unbiased estimate of f_p. Their exact sampling density has no closed form, so `pdf` is a deterministic
//    proxy used only in MIS weights (both strategies use the same function, so the weights still sum to
//    one).
//  - `sample` returns the direction with its value and density, like a BSDF sample (bsdf.h): the path's
//    throughput is multiplied by weight() = f / pdf. For deterministic phase functions f = f_p(wo, wi) and pdf
//    is the true density (equal when f_p is sampled exactly); for a stochastic one f is the value that makes
//    f / pdf the exact weight f_p / density of what was sampled (f = pdf when it samples f_p exactly).
#pragma once

#include "core/math.h"
#include "core/rng.h"

namespace kozu {

struct PhaseSample {
  Vec3 wi{0.0f};
  float f = 0;    // f_p(wo, wi) (see above for stochastic phase functions)
  float pdf = 0;  // pdf(wo, wi): the density, or the MIS proxy of a stochastic phase function
  bool valid() const { return pdf > 0.0f && f > 0.0f; }
  float weight() const { return f / pdf; }
};

class PhaseFunction {
 protected:
  ~PhaseFunction() = default;  // lives in an arena or inside a medium; never deleted through this

 public:
  virtual float eval(const Vec3& wo, const Vec3& wi, Pcg32& rng) const = 0;
  virtual PhaseSample sample(const Vec3& wo, const Vec2& u, Pcg32& rng) const = 0;
  virtual float pdf(const Vec3& wo, const Vec3& wi) const = 0;
  // The axis that orients the scatterers, for the denoiser's normal feature (render/aov.h) where a path's first
  // vertex is in a medium: zero for phase functions without one.
  virtual Vec3 feature_axis() const { return Vec3(0.0f); }
};

}  // namespace kozu
