// LEAN mapping (M. Olano and D. Baker, "LEAN Mapping", I3D 2010): a normal map stored as the first and second
// moments of its slopes, B = (x̃, ỹ) and M = (x̃², ỹ², x̃ỹ) with x̃ = −n_x / n_z, ỹ = −n_y / n_z, which filter
// linearly (any mip level or footprint is the mean of its texels' moments). A footprint's lobe is the Gaussian
// (Beckmann) distribution of slopes with mean B and covariance Σ = M − B Bᵀ + σ₀² I, σ₀² = α₀² / 2 the base
// surface's own slope variance per axis (eqs. 7–9 of the paper; anisotropic, with the correlation term).
//
// kozu ships Chan 2018's shortened normals (normal_gloss_filter.h), which keep GGX and one gloss channel; LEAN is
// here as the classic baseline docs/wwii.md compares against (tests/textures/test_normal_filter_comparison.cpp),
// not used by the renderer. Masking is not part of LEAN; `lambda` gives Smith's Λ of the centred Gaussian with the
// covariance's variance along the direction's azimuth (Beckmann's Λ with α_φ² = 2 σ_φ²), a choice of this file.
#pragma once

#include "core/math.h"

namespace kozu {

struct LeanMoments {
  double b[2] = {0, 0};     // mean slope (x̃, ỹ)
  double m[3] = {0, 0, 0};  // mean of x̃², ỹ², x̃ỹ
  double count = 0;
  // Adds a texel's unit normal (n_z > 0), in tangent space.
  void add(const Vec3& n);
  void add(const LeanMoments& other);
};

class LeanLobe {
 public:
  LeanLobe(const LeanMoments& moments, double base_alpha);
  // The distribution of microfacet normals in the macro surface's frame (z up), per unit solid angle.
  double D(const Vec3& m) const;
  // Smith Λ for direction w (see the top of this file).
  double lambda(const Vec3& w) const;
  // A normal drawn with pdf D(m) cos θ_m (slopes from the Gaussian), from two uniform numbers.
  Vec3 sample(double u1, double u2) const;
  // The mean-slope normal normalize(−B.x, −B.y, 1) (the level's shading normal in LEAN).
  Vec3 mean_normal() const;
  double sxx() const { return sxx_; }
  double syy() const { return syy_; }
  double sxy() const { return sxy_; }

 private:
  double bx_, by_, sxx_, syy_, sxy_;
  double lxx_, lyx_, lyy_;  // Cholesky factor of Σ
  double det_;
};

}  // namespace kozu
