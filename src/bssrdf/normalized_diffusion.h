// normalized_diffusion: Burley's normalized-diffusion reflectance profile with Christensen & Burley's
// three parameterizations of its width, and exact importance sampling of the radius.
//
// Citation: Christensen & Burley 2015, "Approximate Reflectance Profiles for Efficient Subsurface
// Scattering", Pixar Technical Memo #15-04, 2015.
// Equation map:
//   eval            R(r) = A (e^{-r/d} + e^{-r/(3d)}) / (8 π d r)                      eq. (2), (3) with d = ℓ/s
//   scale s(A)      searchlight 1.85 − A + 7|A − 0.8|³                               eq. (5)
//                   diffuse     1.9 − A + 3.5 (A − 0.8)²                             eq. (6)
//                   dmfp        3.5 + 100 (A − 0.33)⁴  (ℓ is then the dmfp ℓd)        eq. (8)
//   cdf             1 − e^{-r/d}/4 − 3 e^{-r/(3d)}/4                                 eq. (9)–(11)
//   pdf             R(r) 2πr / A = (e^{-r/d} + e^{-r/(3d)}) / (4d)                   derivative of eq. (11)
//   sample          eq. (11) inverted: with x = e^{-r/(3d)} it reads x³ + 3x = 4(1 − u), a depressed cubic
//                   with one real root; Newton's method from x0 = min(1, 4(1 − u)/3), which lies right of
//                   the root so the convex cubic converges monotonically (≤ 5 steps to 1e-15), r = −3d ln x.
//   sample_closed_form  the same root in closed form, x = 2 sinh(asinh(2(1 − u))/3) (hyperbolic form of Cardano's
//   formula, free of cancellation).
// Both run in double: near u = 0 the root x is 1 − 2u/3 and float would lose r's leading digits.
// bench/bench_subsurface.cpp times the two on the same inputs: Newton takes 0.71× the closed form's time
// (sinh and asinh cost more than five polynomial steps) and they agree to 1.2e-13, so Newton is `sample`.
#pragma once

#include <cstdint>

namespace kozu {

enum class SubsurfaceParameterization { Searchlight, Diffuse, Dmfp };

namespace normalized_diffusion {
// The scale s that maps the surface albedo A to d = ℓ/s (ℓ the mfp, or the dmfp for Dmfp).
double scale(SubsurfaceParameterization p, double A);
}  // namespace normalized_diffusion

// One color channel's profile: surface albedo A and shape parameter d (a length).
class NormalizedDiffusion {
 public:
  NormalizedDiffusion() = default;
  NormalizedDiffusion(float A, float d) : A_(A), d_(d) {}
  // From a user-facing length ℓ (mfp or dmfp, per the parameterization): d = ℓ / s(A).
  static NormalizedDiffusion from_length(SubsurfaceParameterization p, float A, float length);

  // R(r) per unit area (eq. 3); integrates to A over the plane.
  float eval(float r) const;
  // Density of the radius r (per unit length) of R(r) 2πr / A.
  float pdf(float r) const;
  double cdf(double r) const;
  // The radius with cdf(r) = u, u in [0, 1).
  float sample(float u, int* iterations = nullptr) const;
  float sample_closed_form(float u) const;
  // The radius that holds the fraction q of the profile's energy (probe rays stop there).
  float radius_of_fraction(float q) const { return sample(q); }

  float albedo() const { return A_; }
  float d() const { return d_; }

 private:
  float A_ = 0.0f;
  float d_ = 1.0f;
};

}  // namespace kozu
