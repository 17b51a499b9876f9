// Detail gloss: the gloss of a base normal map's texel combined with the gloss of a detail normal map blended into
// it, by multiplying their shortened-normal lengths.
//
// Source: D. Chan, "Material Advances in Call of Duty: WWII", SIGGRAPH 2018 course Advances in Real-Time Rendering
// in Games, §2.4 (eqs. (28)-(37)); the lengths are the macro-surface model's, eq. (26)
// (textures/normal_gloss_filter.h).
//
// Equation map (L = GlossToNormalLength of Algorithm 3, macro model; g_a the base gloss, g_b the detail gloss):
//   n_a = (1/N) sum n_a,i,  n_b = (1/M) sum n_b,j            eqs. (28), (29)  the two NDFs' shortened normals
//   n_s = (1/M) sum_j (1/N) sum_i n_a,i|b,j                   eq. (30)         (tested by sampling: test_detail_gloss)
//   |n_s| = |n_a| |n_b|                                      eqs. (31)-(34)   detail_gloss_exact
//   g = NormalLengthToGloss(L(g_a) L(g_b)), 0 below L(0)     eq. (34)         detail_gloss_exact, DetailGlossTable
//   g = clamp(P(g_a, g_b) / Q(g_a, g_b), 0, 1)               eqs. (35)-(37)   detail_gloss_fit
//
// Parameters
//   method  "exact" (eq. 34) or "fit" (eq. 37 with the paper's coefficients of eqs. 35-36)
//
// Choices. detail_gloss_exact inverts eq. (26) exactly (normal_length_to_gloss: a table and regula falsi, about a
// microsecond); the renderer's path, DetailGlossTable, does the same with two tables of 4097 entries and linear
// interpolation: e(g) = 1 - L(g) over g, and g over ln e (1 - L spans 1/3 down to 4.2e-5, where a table in L itself
// would need millions of entries near g = 1); 1 - L_a L_b = e_a + e_b - e_a e_b keeps the digits that the product
// near 1 would lose. Its largest difference from detail_gloss_exact is measured in test_detail_gloss (below 1e-5).
// Eq. (34) as the paper has it: a detail gloss of 1 (a detail map's level 0) still lowers the base gloss a little,
// since L(1) = 0.999958 < 1 (eq. (2) has no α = 0).
#pragma once

#include <array>

namespace kozu {

// Chan 2018 eq. (34), exact: the gloss whose macro shortened length is L(g_a) L(g_b); 0 when the product is below
// L(0) = 2/3. Inputs clamped to [0, 1].
double detail_gloss_exact(double ga, double gb);

// The coefficients of eqs. (35)-(36): P = p0 + p1 (a + b) + p2 (a² + b²) + p3 ab, Q likewise with q0 = 1.
struct DetailGlossFit {
  std::array<double, 4> p, q;
};
// The paper's, eqs. (35)-(36).
inline constexpr DetailGlossFit kDetailGlossFitPaper{{-0.535580, 1.002204, -0.223910, 13.323150},
                                                     {1.0, 8.259559, 9.896132, -22.015902}};
// kozu fit-rational's least-squares refit on the same 32 x 32 table (docs/wwii.md, "The paper's fits, redone").
inline constexpr DetailGlossFit kDetailGlossFitKozu{{-0.5642, 0.990307, -0.12033, 15.0342},
                                                    {1.0, 9.33113, 11.0867, -24.5274}};
// Chan 2018 eq. (37): clamp(P / Q, 0, 1).
double detail_gloss_fit(double ga, double gb, const DetailGlossFit& fit = kDetailGlossFitPaper);

// Eq. (34) by tables, for lookups (see the top of this file). Thread-safe after construction.
class DetailGlossTable {
 public:
  static const DetailGlossTable& instance();
  float combine(float ga, float gb) const;

 private:
  DetailGlossTable();
  static constexpr int kSize = 4097;
  std::array<float, kSize> e_;      // 1 - L(i / (kSize - 1))
  std::array<float, kSize> gloss_;  // the gloss at ln e = log_e_min_ + i * step
  float log_e_min_ = 0, log_e_max_ = 0, e_max_ = 0;
};

}  // namespace kozu
