// semi_infinite_mc: brute-force Monte Carlo reference for the radial reflectance profile R(r) of a
// semi-infinite homogeneous medium below a flat, index-matched surface (no Fresnel), isotropic phase
// function, lit by a searchlight (along the normal) or by diffuse (cosine-distributed) transmission.
//
// Citation: L. Wang, S. L. Jacques, L. Zheng 1995, "MCML — Monte Carlo modeling of light transport in
// multi-layered tissues", Computer Methods and Programs in Biomedicine 47, 131–146 (implicit capture,
// Russian roulette); Christensen & Burley 2015 § 3.1, whose
// reference profiles this reproduces. The dmfp (§ 5): D = (σt + σa) / (3 σt²) eq. (7), σtr = sqrt(σa / D),
// ℓd = 1 / σtr.
//
// Model: σt = 1/ℓ, σs = α σt, σa = (1 − α) σt. A photon starts at the origin heading into z < 0, straight
// down (searchlight) or cosine-distributed about −z (diffuse). Free flights are −ln(u)/σt; a flight that
// crosses z = 0 leaves the medium and scores at the radius of the exact crossing point. Otherwise the photon
// scatters isotropically.
//
// Estimator: implicit capture (the weight is multiplied by α at each collision, the path never ends by
// absorption), Russian roulette once the weight falls below `roulette_weight` (survive with probability
// `roulette_survival`, weight divided by it: unbiased), and a cap of `max_collisions` per photon; the weight
// a capped photon still carries is reported as `truncated` (at α = 1 the number of collisions before escape
// has an infinite mean, P(N > n) ~ n^{-1/2}). Each photon scores at most once, so per bin Σw and Σw² over
// photons give the mean and its standard error; A is the total exiting weight per photon, including what
// leaves below r_min and beyond r_max.
//
// Parallelism and determinism: photons are split into chunks of `chunk_photons`; chunk k draws from its own
// PCG32 stream seeded from (seed, k), and chunk histograms are summed in chunk order, so the result is the
// same bit for bit for any thread count.
//
// Parameters (SemiInfiniteMcSettings):
//   name              type     default      range / meaning
//   albedo            double   0.5          α ∈ [0, 1], single-scattering albedo σs/σt
//   mfp               double   1            ℓ > 0, volume mean free path 1/σt (same length unit as the radii)
//   illumination      enum     Searchlight  Searchlight | Diffuse
//   photons           uint64   10⁶          > 0
//   seed              uint64   1
//   bins              RadialBins {0.01, 10, 48}  log-spaced [r_min, r_max] (count bins)
//   dmfp_bins         optional none         a second histogram of r / ℓd (needs α < 1)
//   max_collisions    int      10⁵          collisions per photon before it is truncated
//   roulette_weight   double   10⁻⁴         MCML's threshold
//   roulette_survival double   0.1          MCML's chance
//   chunk_photons     uint64   2048         photons per deterministic chunk
#pragma once

#include "tools/chandrasekhar_h.h"

#include <cstdint>
#include <optional>
#include <vector>

namespace kozu {

// Log-spaced radial bins: bin i covers [r_min q^i, r_min q^{i+1}), q = (r_max / r_min)^{1/count}.
struct RadialBins {
  double r_min = 0.01;
  double r_max = 10.0;
  int count = 48;

  double edge(int i) const;
  // The bin of radius r: −1 below r_min, count at or beyond r_max.
  int index(double r) const;
};

// Σw and Σw² per bin over photons, plus what leaves below r_min and beyond r_max.
struct RadialHistogram {
  RadialBins bins;
  std::vector<double> sum_w, sum_w2;
  double below_w = 0.0, below_w2 = 0.0, above_w = 0.0, above_w2 = 0.0;

  RadialHistogram() = default;
  explicit RadialHistogram(const RadialBins& b);
  void add(double r, double w);
  void merge(const RadialHistogram& other);
};

// One bin of a profile, all quantities per photon (unit incident power).
struct ProfileBin {
  double r_lo, r_hi;
  double r_mid;      // geometric mean of the edges
  double R, R_se;    // annulus average Σw / (N π (r_hi² − r_lo²)) and its standard error
  double rR, rR_se;  // r_mid · R
};

struct SemiInfiniteMcSettings {
  double albedo = 0.5;
  double mfp = 1.0;
  SubsurfaceIllumination illumination = SubsurfaceIllumination::Searchlight;
  uint64_t photons = 1000000;
  uint64_t seed = 1;
  RadialBins bins;
  std::optional<RadialBins> dmfp_bins;
  int max_collisions = 100000;
  double roulette_weight = 1e-4;
  double roulette_survival = 0.1;
  uint64_t chunk_photons = 2048;
};

struct SemiInfiniteMcResult {
  SemiInfiniteMcSettings settings;
  double A = 0.0, A_se = 0.0;                  // total exiting weight per photon (the surface albedo)
  double truncated = 0.0, truncated_se = 0.0;  // weight per photon still in the medium at the collision cap
  double below = 0.0, above = 0.0;             // parts of A leaving below r_min and beyond r_max
  double mean_collisions = 0.0;
  double dmfp = 0.0;                              // ℓd of the medium (infinite at α = 1)
  RadialHistogram histogram;                      // radii in units of the length (ℓ = mfp)
  std::optional<RadialHistogram> dmfp_histogram;  // radii in units of ℓd

  std::vector<ProfileBin> profile() const { return profile_of(histogram); }
  // Empty without dmfp_bins.
  std::vector<ProfileBin> dmfp_profile() const {
    return dmfp_histogram ? profile_of(*dmfp_histogram) : std::vector<ProfileBin>{};
  }
  std::vector<ProfileBin> profile_of(const RadialHistogram& h) const;
};

// Runs the simulation with oneTBB on the current task arena. Throws std::invalid_argument on bad settings.
SemiInfiniteMcResult simulate_semi_infinite(const SemiInfiniteMcSettings& settings);

// The diffuse mean free path ℓd = 1 / σtr of a medium with single-scattering albedo α and σt:
// D = (σt + σa) / (3 σt²) (eq. 7), σtr = sqrt(σa / D). Infinite at α = 1.
double diffuse_mean_free_path(double alpha, double sigma_t);

}  // namespace kozu
