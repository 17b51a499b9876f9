// The prefiltered texture of a textured polygonal light and its fetch, for LTC shading (Heitz et al. 2016 §5.2–5.4).
//
// Citation: Heitz, Dupuy, Hill, Neubelt 2016, "Real-Time Polygonal-Light Shading with Linearly Transformed
// Cosines", ACM TOG 35(4), SIGGRAPH 2016.
//   I   ≈ ∫_P L D dω = I_D I_L                                          eq. (12)
//   I_D = ∫_P D dω                       (Ltc::integrate_polygon)       eq. (13)
//   I_L = ∫_P L D dω / ∫_P D dω = ∫_{P_o} L_o D_o dω / ∫_{P_o} D_o dω   eqs. (14), (15)
// I_L is the light's texture filtered by D restricted to P. §5.3 replaces that filter by a texture-space Gaussian
// clamped to the texture and renormalized:
//   L_σ(x) = Σ_{y ∈ texture} G_σ(x − y) L(y) / Σ_{y ∈ texture} G_σ(x − y),
// kept as a pyramid of levels σ_k = 2^k / N (k ≥ 1; level 0 is the texture itself) over texture space with a
// margin around it (x outside [0, 1]², where the renormalized Gaussian still reaches the texture; beyond the
// margin the coordinates are clamped to its edge). The Gaussian is separable and so is the clamp, so each level is
// two 1D passes whose weights are normalized per output position (taken relative to the nearest texel, so far
// outside the texture they cannot underflow: there the level tends to the nearest edge's value, as the clamped
// filter does).
// §5.4: in the cosine configuration (the light's frame transformed by M⁻¹) the fetch is at the orthogonal
// projection of the shading point on the light's plane, at the level σ = sqrt(r² / (2A)) with r the distance to
// the plane and A the area of the texture's square there (texture units: the square is 1 × 1), trilinearly between
// levels.
#pragma once

#include "core/color.h"
#include "core/math.h"

#include <span>
#include <vector>

namespace kozu {

class Ltc;

class LtcTexture {
 public:
  // texels: n × n linear RGB values of the light's texture over its square (a, b) ∈ [0, 1]², row b-major (texel
  // (i, j) covers a ∈ [i/n, (i+1)/n), b ∈ [j/n, (j+1)/n)), finite and non-negative.
  LtcTexture(std::span<const Rgb> texels, int n);

  // I_L of eq. (15) for the distribution ltc and the light whose texture square is o + a e1 + b e2, with o, e1,
  // e2 in ltc's frame relative to the shading point.
  Rgb fetch(const Ltc& ltc, const Vec3& o, const Vec3& e1, const Vec3& e2) const;

  // The prefiltered texture L_σ at (a, b) (texture units; σ = 0: the texture, bilinear, clamped to its edge).
  Rgb lookup(const Vec2& ab, float sigma) const;
  // The filter width in texture units, and where on the square, of the fetch for ltc (§5.4).
  static float fetch_sigma(const Ltc& ltc, const Vec3& o, const Vec3& e1, const Vec3& e2, Vec2* ab);

  int levels() const { return int(levels_.size()); }
  float level_sigma(int k) const { return levels_[size_t(k)].sigma; }
  // The margin around the texture square that the levels cover, in texture units.
  static constexpr float kMargin = 0.5f;

 private:
  struct Level {
    float sigma = 0;     // 0 for the texture itself
    float origin = 0;    // texture coordinate of sample 0 along a and b
    float spacing = 0;   // between samples
    int size = 0;        // samples along a and b
    std::vector<Rgb> v;  // size × size, row b-major
    Rgb bilinear(const Vec2& ab) const;
  };
  std::vector<Level> levels_;
};

}  // namespace kozu
