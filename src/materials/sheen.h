// sheen: the "Charlie" sheen lobe of cloth-like surfaces (dust, velvet, fabric fuzz), a lobe of the standard
// material (standard.h) as glTF's KHR_materials_sheen defines it.
//
// Citations: Estevez & Kulla 2017, "Production Friendly Microfacet Sheen BRDF" (the "Charlie" distribution, their
// eq. (2)); Heitz 2014, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs" (Smith Λ from the
// projected area, eqs. (17), (72); height-correlated G2, eq. (99)); the Khronos KHR_materials_sheen specification
// (α = sheen_roughness², albedo scaling of the layers below).
// Equation map (n = +z, h = normalize(ωo + ωi), μ = cos θ, α = r²):
//   D(m)       = (2 + 1/α) sin(θm)^(1/α) / (2π)                       Estevez & Kulla eq. (2); ∫ D cos θm dm = 1
//   σ(μ)       = ∫ max(0, ω·m) D(m) dm,   Λ(μ) = σ(μ) / μ − 1          Heitz 2014 (17), (72): exact Smith masking,
//                                                                   tabulated at first use (64 μ × 32 r nodes)
//   G2         = 1 / (1 + Λ(μo) + Λ(μi))                               Heitz 2014 (99)
//   f cos θi   = color D(h) G2 / (4 μo)                                reciprocal: symmetric in ωo, ωi
//   E(μ, r)    = ∫ f cos θi dωi for color = 1                           ≤ 1 (single scattering); tabulated below
// Deviation from the paper: Estevez & Kulla fit Λ with a closed form (their Table 1) for speed; kozu uses the exact
// Λ of the same distribution from a table. The cheaper "Ashikhmin" visibility 1 / (4 (μi + μo − μi μo)) of some
// real-time viewers is not bounded: its albedo reaches 3.2 at μ = 0.016, r = 0.085 (measured), which no albedo
// scaling can absorb.
// The layers under the sheen are scaled by (1 − max(color) E(μo)) (1 − max(color) E(μi)) (standard.h), so the sum
// never exceeds the base's albedo.
// Sampled with the cosine-weighted hemisphere (diffuse.h): the lobe is broad, with no peak to chase.
//
// Deviation: r is clamped to [kMinRoughness, 1]: below it D is a spike at grazing half vectors that the albedo
// table (and any sampler) cannot resolve; glTF viewers clamp it likewise.
#pragma once

#include "core/color.h"
#include "core/frame.h"

namespace kozu::sheen {

inline constexpr float kMinRoughness = 0.07f;

// f cos θi for color = 1, wo and wi on the +z side (0 otherwise).
float eval(const Vec3& wo, const Vec3& wi, float roughness);

// E(μ, r): the directional albedo of eval, from a table of 32 × 32 nodes (μ = (i/31)², r = r_min + (1 − r_min)
// (j/31)²: E bends most near μ = 0 and at small r) integrated numerically on first use, bilinear.
float albedo(float mu, float roughness);

// The same integral computed directly (Gauss–Legendre in cos θi times the trapezoid rule in φ, n × 2n points):
// what the table holds at its nodes, and what the tests compare it against off the nodes.
double integrate_albedo(float mu, float roughness, int n);

}  // namespace kozu::sheen
