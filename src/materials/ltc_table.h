// The fitted LTC tables the renderer uses (`kozu fit-ltc … -o src/materials/ltc_<brdf>_data.inc`, checked in) and
// their lookup: the LTC of a lobe seen from θ_v at roughness α, with its norm and Fresnel norm. Three lobes, each
// for GGX and Beckmann:
//   ggx, beckmann            the single-scattering conductor lobe (F = 1); with Schlick's Fresnel of reflectance
//                            F0 its albedo is F0 n + (1 − F0) n_F (§4)
//   *-compensated            kozu's compensated conductor (F = 1): single scattering plus ushiostarfish 2018's coupled
//   lobe,
//                            whose albedo is 1; the renderer takes the shape from it and the energy from the
//                            single-scattering norms plus the coupled lobe's exact albedo
//   *-specular               the dielectric specular lobe of plastic and standard (Fresnel of IOR 1.5, single
//                            scattering); its norm is the lobe's albedo E_R at IOR 1.5, the materials weight it
//                            by their own E_R tables
//
// Citation: Heitz, Dupuy, Hill, Neubelt 2016, "Real-Time Polygonal-Light Shading with Linearly Transformed
// Cosines", ACM TOG 35(4), §4 "Fitting" and
// "Representation and Storage" (M⁻¹ normalised by its (2, 2) entry; a 64 × 64 grid over θ_v and √α; bilinear
// interpolation of the stored M⁻¹ entries).
#pragma once

#include "core/ltc.h"

namespace kozu {

enum class LtcBrdf { Ggx, Beckmann, GgxCompensated, BeckmannCompensated, GgxSpecular, BeckmannSpecular };
inline constexpr LtcBrdf kLtcBrdfs[] = {
    LtcBrdf::Ggx,         LtcBrdf::Beckmann,        LtcBrdf::GgxCompensated, LtcBrdf::BeckmannCompensated,
    LtcBrdf::GgxSpecular, LtcBrdf::BeckmannSpecular};

// The name of kozu fit-ltc --brdf ("ggx", "beckmann-compensated", "ggx-specular", …).
const char* ltc_brdf_name(LtcBrdf brdf);

// One entry of a checked-in table (the layout kozu fit-ltc writes).
struct LtcTableEntry {
  float m00, m02, m11, m20;  // M⁻¹ / (M⁻¹)₂₂: the other entries are 0, (2, 2) is 1
  float norm, fresnel_norm;
  float error;  // the fit's L1 error ∫ |D − F| dω (0 perfect, 2 disjoint)
};

struct LtcLobeFit {
  Ltc ltc;  // in the frame whose x axis is the view's azimuth (the view in the xz plane)
  float norm = 0, fresnel_norm = 0;
};

constexpr int kLtcTableSize = 64;

// From this α up, one lobe of the compensated table approximates kozu's compensated conductor better (relative L1
// over the hemisphere) than the single-scattering lobe plus the coupled lobe as a clamped cosine; below it, the
// pair is better (GGX: summed over four views, 0.363 against 0.287 at α 0.45, 0.174 against 0.222 at 0.65;
// tests/materials/test_ltc_lobes.cpp). The L³ fit favours the peak, which a narrow lobe's coupled part is not.
constexpr float kLtcCompensatedMinAlpha = 0.6f;

// The table's entry i * size + j (α index i, θ_v index j), for tests and tools.
const LtcTableEntry& ltc_table_entry(LtcBrdf brdf, int i, int j);

// The lobe seen from cos θ_v (> 0) at roughness α, bilinear in (θ_v, √α) between the table's entries.
LtcLobeFit ltc_lookup(LtcBrdf brdf, float cos_theta_v, float alpha);

// The norm and Fresnel norm alone (bilinear, as ltc_lookup).
void ltc_norms(LtcBrdf brdf, float cos_theta_v, float alpha, float* norm, float* fresnel_norm);

// The LTC of the lobe for the view wo (local shading frame, wo.z > 0): lookup, then rotated from the view's frame
// into the shading frame.
LtcLobeFit ltc_lobe(LtcBrdf brdf, const Vec3& wo, float alpha);

}  // namespace kozu
