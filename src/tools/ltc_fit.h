// Fitting linearly transformed cosines to a BRDF: for each view angle θ_v and roughness α of a grid, the matrix M
// of eq. (6), M = [[a, 0, b], [0, c, 0], [d, 0, 1]], whose LTC D (lights/ltc.h) best matches the normalised
// cosine-weighted BRDF F(ω) = ρ(ω_v, ω) cos θ / n, n = ∫ ρ cos dω (eq. 5), in the paper's L³ error.
//
// Citation: Heitz, Dupuy, Hill, Neubelt 2016, "Real-Time Polygonal-Light Shading with Linearly Transformed
// Cosines", ACM TOG 35(4), §4 "Fitting" (eq. 5,
// 6, the L³ error) and "Representation and Storage" (M⁻¹ and the norm; a 64 × 64 grid over θ_v ∈ [0, π/2] and
// √α ∈ [0, 1]).
//
// kozu's procedure:
//   grid        θ_v = j/(N − 1) · π/2 (at most 1.57), α = max((i/(N − 1))², 1e-3) (MicrofacetDistribution::kMinAlpha)
//   view        ω_v = (sin θ_v, 0, cos θ_v): the lobe lies in the xz plane, symmetric in y, as eq. (6) assumes
//   error       E(M) = ∫ |D(ω) − F(ω)|³ dω, estimated with a fixed set of stratified samples from D and from the
//               BRDF's own sampler, combined by the balance heuristic (the same points at every step, so E is a
//               deterministic function of M for the minimiser)
//   minimiser   Nelder–Mead over (a, b, c, d) (tools/nelder_mead.h), each column of θ_v from α = 1 down, every
//               fit started from the previous α's result (the LTC narrows smoothly with α)
//   stored      M⁻¹ divided by its (2, 2) entry (the LTC is scale invariant, §3.1), so it has eq. (6)'s form too;
//               the norm n; the Fresnel-weighted norm n_F = ∫ ρ cos (1 − ω_v·h)⁵ dω, so that under Schlick's
//               Fresnel the norm is F0 n + (1 − F0) n_F with the BRDF fitted for F = 1; and the fit's L1 error
//               ∫ |D − F| dω ∈ [0, 2], reported beside each entry.
#pragma once

#include "core/math.h"
#include "materials/bsdf.h"
#include "materials/ltc_table.h"

#include <functional>
#include <string>
#include <vector>

namespace kozu {

class Arena;

struct LtcFitEntry {
  float a = 1, b = 0, c = 1, d = 0;  // M, eq. (6)
  float norm = 0, fresnel_norm = 0;
  float error = 0;  // ∫ |D − F| dω, 0 (perfect) to 2 (disjoint)
  Mat3 m() const;
  Mat3 m_inv_normalized() const;  // M⁻¹ / (M⁻¹)₂₂
};

// The lobe to fit at one roughness: a BSDF whose eval is ρ cos θ (its green channel is used; fit with F = 1).
using LtcTargetBsdf = std::function<const Bsdf*(float alpha, Arena& arena)>;

// The lobe each table of lights/ltc_table.h is fitted to, for the roughnesses of a size × size grid: kozu's rough
// conductor with F = 1 (single scattering, or compensated with ushiostarfish 2018's coupled lobe), or its plastic with
// an albedo of 0 (the dielectric specular lobe, IOR 1.5). The per-roughness tables are built once, here.
LtcTargetBsdf ltc_target(LtcBrdf brdf, int size);

// The lobe's norm n = ∫ ρ cos dω by the material's own albedo tables (for the tests): E(μ, α) for the single-
// scattering conductor, E_R(μ, α) at IOR 1.5 for the specular lobe, E + 1 − E_table for the compensated conductor;
// quadratures of 256² points (128² left Beckmann at α 0.38 2.1e-3 off the fit's own 256²-sample norm).
float ltc_target_norm(LtcBrdf brdf, float cos_theta_v, float alpha);

struct LtcFitOptions {
  int size = 64;         // N × N entries
  int fit_samples = 32;  // per strategy, per dimension, during the minimisation
  int report_samples =
      256;          // per strategy, per dimension, for the norms and the reported error (96: norms 2e-3 off at α 0.1)
  int threads = 0;  // 0: all
};

// One entry: the BSDF seen from w_v, the fit started from `start`.
LtcFitEntry fit_ltc_entry(const Bsdf& bsdf, const Vec3& wv, const LtcFitEntry& start, const LtcFitOptions& options);

// The L1 error ∫ |D − F| dω of the LTC of e's matrix against the BSDF seen from w_v (n × n samples per strategy).
float ltc_fit_error(const Bsdf& bsdf, const Vec3& wv, const LtcFitEntry& e, int n);

// The whole table, row-major: entries[i * size + j] for α index i and θ_v index j.
std::vector<LtcFitEntry> fit_ltc_table(const LtcTargetBsdf& target, const LtcFitOptions& options);

// The grid of fit_ltc_table.
float ltc_table_theta(int j, int size);
float ltc_table_alpha(int i, int size);

}  // namespace kozu
