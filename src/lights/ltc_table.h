// The fitted LTC tables the renderer uses (`kozu fit-ltc … -o src/lights/ltc_<brdf>_data.inc`, checked in) and
// their lookup: the LTC of the single-scattering GGX or Beckmann lobe (F = 1) seen from θ_v at roughness α, with
// its norm and Fresnel norm, so that a lobe with Schlick's Fresnel of reflectance F0 has ∫ ρ cos dω ≈
// F0 n + (1 − F0) n_F (seed §4).
//
// Citation: Heitz, Dupuy, Hill, Neubelt 2016 (seed ../shared/seeds/003_de419075ed848e43.txt), §4 "Fitting" and
// "Representation and Storage" (M⁻¹ normalised by its (2, 2) entry; a 64 × 64 grid over θ_v and √α; bilinear
// interpolation of the stored M⁻¹ entries).
#pragma once

#include "lights/ltc.h"

namespace kozu {

enum class LtcBrdf { Ggx, Beckmann };

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

// The table's entry i * size + j (α index i, θ_v index j), for tests and tools.
const LtcTableEntry& ltc_table_entry(LtcBrdf brdf, int i, int j);

// The lobe seen from cos θ_v (> 0) at roughness α, bilinear in (θ_v, √α) between the table's entries.
LtcLobeFit ltc_lookup(LtcBrdf brdf, float cos_theta_v, float alpha);

// The LTC of the lobe for the view wo (local shading frame, wo.z > 0): lookup, then rotated from the view's frame
// into the shading frame.
LtcLobeFit ltc_lobe(LtcBrdf brdf, const Vec3& wo, float alpha);

}  // namespace kozu
