// Normal and gloss mip filtering by shortened normals: each coarser mip level of a normal map and its gloss map is
// built from the shortened (averaged, no longer unit) normals of the level below, and the shortened length is
// turned back into gloss, so that the bumps a level can no longer show become roughness.
//
// Source: D. Chan, "Material Advances in Call of Duty: WWII", SIGGRAPH 2018 course Advances in Real-Time Rendering
// in Games, §2 (eqs. (2)-(27), Algorithms 1-3).
//
// Equation map (n = +z is the macro-surface normal, g the WWII gloss, a = sqrt(1 - alpha^2)):
//   alpha = sqrt(2 / (1 + 2^(18 g)))                         eq. (2)          wwii_gloss_to_alpha / _alpha_to_gloss
//   n_s = (1/N) sum n_i, the shortened normal                eq. (3)          downsample_normal_gloss (macro)
//   micro-surface model |n_s| = 1 / int D dw                 eqs. (4)-(12), (23), (24)  shortened_normal_length_micro
//   texel micro-surface area dA / cos(theta)                 eq. (13)         downsample_normal_gloss (micro)
//   macro-surface model |n_s| = int D cos^2 dw               eqs. (14)-(18), (25), (26) shortened_normal_length_macro
//   a = sqrt(1 - alpha^2)                                    eq. (27)
//   GlossToNormalLength / NormalLengthToGloss                Algorithm 3      gloss_to_normal_length /
//                                                                             normal_length_to_gloss
//   micro-surface-area averaging of a footprint              Algorithm 1      downsample_normal_gloss (Micro)
//   macro-surface-area (plain) averaging of a footprint      Algorithm 2      downsample_normal_gloss (Macro)
//   the mip chain: average, length -> gloss, renormalise     Algorithm 3      filter_normal_gloss
//   the paper's rational fits of the macro table             eqs. (40), (42)  gloss_to_normal_length_fit
//
// Parameters
//   model   ShortenedNormalModel  Macro  Macro (Algorithm 2, as shipped in the game) or Micro (Algorithm 1)
//
// Deviations and choices
//   - NormalLengthToGloss is the exact inverse of the closed form (eq. 24 or 26 through eq. 2), not the game's table
//     or rational fit: a table of L(i / 4096) brackets the root, regula falsi (Illinois) refines it inside the
//     bracket to 1e-14 of g or 1e-16 of length (the round trip g -> L -> g is within 1e-9 over [0, 1], tested). The
//     fits of eqs. (40), (42) are offered for comparison only (gloss_to_normal_length_fit).
//   - The gloss of eq. 2 spans alpha in [alpha(1) = 0.00276, 1], so a length below L(g = 0) (2/3 macro, 1/2 micro;
//     normals spread wider than the roughest GGX) becomes g = 0, and its lost length is not passed on to the next
//     level (which starts again from g = 0's length). Lengths above L(1) cannot occur (means of vectors of at most
//     that length).
//   - Algorithm 1 weighs a texel by its micro-surface area, dA / (n_z |n_s|_micro) (eq. 13 times eq. 12's area of
//     its own NDF), so its contribution to the sum is n / n_z: n_s = sum(n_i / n_z,i) / sum(1 / (n_z,i L_i)). This
//     is exactly recursive (a level built from the level below equals the average over its whole footprint), since
//     the z component of sum(n_i / n_z,i) is the texel count. n_z is clamped to >= 0.01 (a texel at or below the
//     horizon would weigh infinitely).
//   - The footprint of a texel of the next level is 2 x 2 texels (3 in the last row or column of an odd size),
//     all weighted equally; level sizes are floor(w / 2), floor(h / 2), down to 1 x 1 (OpenEXR's round-down mips).
//   - Level 0 is the input as authored (the normals renormalised): texels are facets, not samples of a smooth
//     surface (Chan 2018 §2.3).
#pragma once

#include <vector>

namespace kozu {

enum class ShortenedNormalModel { Macro, Micro };

// Chan 2018 eq. (2) and its inverse (clamped to [0, 1]), in double precision (materials/roughness.h has the float
// one the materials use).
double wwii_gloss_to_alpha(double gloss);
double wwii_alpha_to_gloss(double alpha);

// The length of the mean micro-facet normal of a GGX NDF of roughness alpha in [0, 1]: micro-surface-area weighting,
// Chan 2018 eq. (24), from 1 / 2 (alpha = 1) to 1 (alpha = 0); macro-surface (projected) area weighting, eq. (26),
// from 2 / 3 to 1.
double shortened_normal_length_micro(double alpha);
double shortened_normal_length_macro(double alpha);
double shortened_normal_length(double alpha, ShortenedNormalModel model);

// Algorithm 3's GlossToNormalLength (the closed form through eq. 2) and NormalLengthToGloss (its exact inverse,
// bracketed by a table and refined by regula falsi; lengths beyond L(0), L(1) clamp to 0, 1).
double gloss_to_normal_length(double gloss, ShortenedNormalModel model);
double normal_length_to_gloss(double length, ShortenedNormalModel model);

// The paper's rational fits of the macro gloss -> length table: eq. (40) (unconstrained) or eq. (42) (f(0), f(1)
// pinned); `equation` is 40 or 42. For comparison with the closed form only.
double gloss_to_normal_length_fit(double gloss, int equation);

// One mip level: unit tangent-space normals (+z out of the surface, x along +u, y along +v: the OpenGL convention
// the renderer decodes) and gloss in [0, 1].
struct NormalGlossLevel {
  int width = 0, height = 0;
  std::vector<float> normal;  // 3 values a texel, row-major
  std::vector<float> gloss;   // 1 value a texel
};

// The next coarser level (floor(w / 2) x floor(h / 2), at least 1 x 1) from `fine`: Algorithm 2 (Macro) or 1
// (Micro) over each footprint, then Algorithm 3's conversion of the shortened length to gloss and renormalisation.
NormalGlossLevel downsample_normal_gloss(const NormalGlossLevel& fine, ShortenedNormalModel model);

// Algorithm 3: level 0 (normals renormalised, gloss as given) and every coarser level down to 1 x 1.
std::vector<NormalGlossLevel> filter_normal_gloss(NormalGlossLevel level0, ShortenedNormalModel model);

}  // namespace kozu
