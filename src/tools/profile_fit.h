// profile_fit: fits the scale s of Burley's normalized-diffusion profile (d = ℓ/s) to Monte Carlo reference
// profiles and reproduces Christensen & Burley's table of mean relative errors for the searchlight, diffuse
// transmission and dmfp parameterizations.
//
// Citation: Christensen & Burley 2015 § 3.2 (the fit criterion
// Σ|R(rᵢ) − R_MC(rᵢ)| / R_MC(rᵢ) and the optimal s per A = 0.01 … 0.99), eq. (3), (5), (6), (8); the reported
// means 4.9 % / 5.5 % (searchlight), 2.6 % / 3.9 % (diffuse), 6.4 % / 7.7 % (dmfp), optimal s / formula.
//
// Procedure (build_profile_table): for each A, α comes from the H-function (chandrasekhar_h.h); one searchlight
// run gives the mfp profile (radii in units of ℓ) and the dmfp profile (radii in units of ℓd), one diffuse run
// the diffuse profile. Each profile is compared bin by bin with the model's exact annulus average
//   R̄ᵢ(s) = A_MC (cdf(r_hi) − cdf(r_lo)) / (π (r_hi² − r_lo²)),  cdf of eq. (11) with d = 1/s,
// where A_MC is the simulation's total albedo (eq. 3 with the measured A); no representative radius is needed.
// The error of s is the mean over the selected bins of |R̄ᵢ(s) − R_MC,ᵢ| / R_MC,ᵢ; s_opt minimises it (log scan of
// s over [0.05, 200], then golden-section search between the scan neighbours of the best point).
// Bin selection: a bin takes part when its Monte Carlo relative standard error is at most `max_relative_se`
// (default 0.05) — bins dominated by noise (the far tail at low albedo) carry no information about s, and a
// noisy R_MC in a denominator biases the mean relative error upward. `noise_floor` reports the mean relative
// error a perfect model would show from that noise alone (sqrt(2/π) × the mean relative standard error).
// Radial-range scan (ProfileTableSettings::rmax_scan): the memo does not state its radii rᵢ, and the error depends on
// how far out they reach. For each listed radius R the same Monte Carlo bins are fitted again, keeping only the bins
// with r_hi ≤ R (a prefix of the log-spaced bins, in units of ℓ or ℓd as above, same selection rule), so a scan
// costs fits only, no extra simulation. The scan is reported beside the main table, which keeps `bins`.
// Regenerate the checked-in table with
//   kozu sss-reference --table --json docs/data/sss_table.json
//       --rmax-scan 1,1.3336,1.7783,2.3714,3.1623,4.217,5.6235,7.499   (one command line)
// (every second bin edge 0.01 · 10^{k/16}, k = 32 … 46, rounded up so that each selects its edge).
#pragma once

#include "bssrdf/normalized_diffusion.h"
#include "tools/semi_infinite_mc.h"

#include <nlohmann/json_fwd.hpp>

#include <functional>
#include <string>
#include <vector>

namespace kozu {

// cdf(r_hi) − cdf(r_lo) of the normalized-diffusion radius distribution (eq. 11) with shape d, computed
// without the cancellation of subtracting two numbers close to 1.
double normalized_diffusion_annulus_fraction(double d, double r_lo, double r_hi);

// The indices of the bins whose relative standard error is at most max_relative_se (and whose R is positive).
std::vector<int> select_bins(const std::vector<ProfileBin>& bins, double max_relative_se);

// Mean over the selected bins of |R̄ᵢ(s) − R_MC,ᵢ| / R_MC,ᵢ for the model of albedo A and d = 1/s (the radii of
// the bins are in units of the parameterization's length).
double mean_relative_error(const std::vector<ProfileBin>& bins, const std::vector<int>& use, double A, double s);

struct ScaleFit {
  double s = 0.0;
  double error = 0.0;
};
ScaleFit fit_scale(const std::vector<ProfileBin>& bins, const std::vector<int>& use, double A);

struct ProfileTableSettings {
  std::vector<double> albedos;  // empty: 0.01, 0.02, …, 0.99
  uint64_t photons = 400000;
  uint64_t seed = 1;
  RadialBins bins;  // used for both the mfp (units ℓ) and the dmfp (units ℓd) profiles
  double max_relative_se = 0.05;
  int max_collisions = 100000;
  std::vector<double> rmax_scan;  // outer radii to refit the same bins with (each in (r_min, r_max])
};

struct ProfileTableRow {
  double A = 0.0;      // target surface albedo
  double alpha = 0.0;  // single-scattering albedo from the H-function
  double A_mc = 0.0, A_mc_se = 0.0, truncated = 0.0;
  double dmfp = 0.0;  // ℓd in units of ℓ
  double s_opt = 0.0, error_opt = 0.0;
  double s_formula = 0.0, error_formula = 0.0;
  int bins_used = 0;
  double noise_floor = 0.0;
};

struct ProfileTableColumn {
  SubsurfaceParameterization parameterization = SubsurfaceParameterization::Searchlight;
  std::vector<ProfileTableRow> rows;
  // Means over the rows with at least 5 selected bins (rows with fewer have NaN fits: too few photons).
  double optimal_s_error = 0.0, formula_error = 0.0;
  int albedos_fitted = 0;
};

// The table refitted over the bins with r_hi ≤ r_max (see the radial-range scan above).
struct ProfileRangeScan {
  double requested = 0.0;                   // the radius asked for
  double r_max = 0.0;                       // the outer edge of the last bin kept
  int bins = 0;                             // bins kept (before the selection by relative standard error)
  std::vector<ProfileTableColumn> columns;  // searchlight, diffuse, dmfp
};

struct ProfileTable {
  ProfileTableSettings settings;
  std::vector<ProfileTableColumn> columns;  // searchlight, diffuse, dmfp
  std::vector<ProfileRangeScan> scans;      // one per settings.rmax_scan entry, in order
  double seconds = 0.0;
};

// The number of leading bins of `bins` whose outer edge lies at or inside r_max (relative tolerance 10⁻⁹, so that
// a radius printed from an edge selects that edge).
int bins_within(const RadialBins& bins, double r_max);

// Runs the simulations (2 per albedo) and the fits. progress, if given, receives one line per albedo.
ProfileTable build_profile_table(const ProfileTableSettings& settings,
                                 const std::function<void(const std::string&)>& progress = {});

// {"searchlight": {"optimal_s_error", "formula_error", "paper": {...}, "per_albedo": [...]}, "diffuse": …,
//  "dmfp": …, "rmax_scan": [{"requested", "r_max", "bins", "searchlight": {"optimal_s_error", "formula_error",
//  "albedos_fitted", "s_opt": [...], "error_opt": [...], "error_formula": [...]}, …}], "settings": {...}}; errors as
// fractions, per-albedo arrays in the order of settings.albedos (null where a row has too few bins).
nlohmann::json table_to_json(const ProfileTable& table);

const char* parameterization_name(SubsurfaceParameterization p);

}  // namespace kozu
