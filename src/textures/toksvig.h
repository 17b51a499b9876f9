// Toksvig's normal-map filtering (M. Toksvig, "Mipmapping Normal Maps", Journal of Graphics Tools 10(3), 2005): the
// mean of a footprint's unit normals is shorter the more they spread, and Toksvig scales the Blinn–Phong exponent s
// of the level's lobe by f_t = |n̄| / (|n̄| + s (1 − |n̄|)) (his eq. for s' = f_t s), the normal renormalised. With
// the usual Blinn–Phong ↔ Beckmann correspondence s = 2 / α² − 2 this adds (1 − |n̄|) / |n̄| ≈ the slope variance
// per axis, σ², to the lobe's α² / 2: α'² ≈ α² + 2 σ². The α found is used as GGX's. kozu ships Chan 2018's shortened
// normals instead (normal_gloss_filter.h: the base gloss enters the mean, and the length is inverted exactly for GGX);
// Toksvig's rule is here as the classic baseline that docs/wwii.md compares against
// (tests/textures/test_normal_filter_comparison.cpp), not used by the renderer.
#pragma once

#include <algorithm>
#include <cmath>

namespace kozu {

// The α of a footprint whose unit normals average to a vector of length mean_length, its texels' own lobes of
// roughness alpha. Clamped to GGX's roughest, α = 1.
inline double toksvig_alpha(double alpha, double mean_length) {
  const double len = std::clamp(mean_length, 1e-6, 1.0);
  const double a2 = std::clamp(alpha * alpha, 1e-12, 1.0);
  const double s = 2.0 / a2 - 2.0;                  // Blinn–Phong exponent of the texels' lobe
  const double ft = len / (len + s * (1.0 - len));  // Toksvig's factor
  return std::min(1.0, std::sqrt(2.0 / (ft * s + 2.0)));
}

}  // namespace kozu
