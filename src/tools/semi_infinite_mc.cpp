#include "tools/semi_infinite_mc.h"

#include "core/rng.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace kozu {

double RadialBins::edge(int i) const {
  if (i <= 0) return r_min;
  if (i >= count) return r_max;
  return r_min * std::pow(r_max / r_min, static_cast<double>(i) / count);
}

int RadialBins::index(double r) const {
  if (!(r >= r_min)) return -1;
  if (r >= r_max) return count;
  int i = static_cast<int>(std::log(r / r_min) / std::log(r_max / r_min) * count);
  // The logarithm can land one bin off at an edge; the edges themselves decide.
  i = std::clamp(i, 0, count - 1);
  if (r < edge(i))
    --i;
  else if (i + 1 < count && r >= edge(i + 1))
    ++i;
  return i;
}

RadialHistogram::RadialHistogram(const RadialBins& b) : bins(b), sum_w(b.count, 0.0), sum_w2(b.count, 0.0) {}

void RadialHistogram::add(double r, double w) {
  const int i = bins.index(r);
  if (i < 0) {
    below_w += w;
    below_w2 += w * w;
  } else if (i >= bins.count) {
    above_w += w;
    above_w2 += w * w;
  } else {
    sum_w[i] += w;
    sum_w2[i] += w * w;
  }
}

void RadialHistogram::merge(const RadialHistogram& o) {
  for (size_t i = 0; i < sum_w.size(); ++i) {
    sum_w[i] += o.sum_w[i];
    sum_w2[i] += o.sum_w2[i];
  }
  below_w += o.below_w;
  below_w2 += o.below_w2;
  above_w += o.above_w;
  above_w2 += o.above_w2;
}

double diffuse_mean_free_path(double alpha, double sigma_t) {
  const double sigma_a = (1.0 - alpha) * sigma_t;
  if (!(sigma_a > 0.0)) return std::numeric_limits<double>::infinity();
  const double D = (sigma_t + sigma_a) / (3.0 * sigma_t * sigma_t);  // eq. (7)
  const double sigma_tr = std::sqrt(sigma_a / D);
  return 1.0 / sigma_tr;
}

namespace {

// Standard error of the mean of N per-photon scores with sums s1 = Σw, s2 = Σw².
double standard_error(double s1, double s2, double n) {
  if (n < 2.0) return 0.0;
  return std::sqrt(std::max(s2 - s1 * s1 / n, 0.0) / (n * (n - 1.0)));
}

// A uniform number in the open interval (0, 1) from 32 random bits: 32 bits are plenty here (a free flight
// longer than −ln 2⁻³³ ≈ 22.9 mean free paths has probability 10⁻¹⁰) and half the cost of a 53-bit double.
inline double uniform_open(Pcg32& rng) { return (static_cast<double>(rng.next_u32()) + 0.5) * 0x1p-32; }

struct ChunkTally {
  RadialHistogram histogram;
  std::optional<RadialHistogram> dmfp;
  double exit_w = 0.0, exit_w2 = 0.0, truncated_w = 0.0, truncated_w2 = 0.0;
  uint64_t collisions = 0;
};

void run_chunk(const SemiInfiniteMcSettings& s, double dmfp, uint64_t chunk, uint64_t count, ChunkTally* t) {
  Pcg32 rng(mix64(s.seed ^ mix64(chunk + 0x632be59bd9b4e019ull)), chunk);
  const double sigma_t = 1.0 / s.mfp;
  const double inv_dmfp = 1.0 / dmfp;
  const double two_pi = 2.0 * std::numbers::pi;
  for (uint64_t p = 0; p < count; ++p) {
    double x = 0.0, y = 0.0, z = 0.0;
    double dx = 0.0, dy = 0.0, dz = -1.0;
    if (s.illumination == SubsurfaceIllumination::Diffuse) {
      // Cosine-distributed about −z: μ = sqrt(u).
      const double mu = std::sqrt(uniform_open(rng));
      const double phi = two_pi * uniform_open(rng);
      const double st = std::sqrt(std::max(0.0, 1.0 - mu * mu));
      dx = st * std::cos(phi);
      dy = st * std::sin(phi);
      dz = -mu;
    }
    double w = 1.0;
    for (int n = 0;; ++n) {
      const double step = -std::log(uniform_open(rng)) / sigma_t;
      const double z_new = z + step * dz;
      if (z_new >= 0.0) {
        // Leaves through z = 0 at the exact crossing point.
        const double t_exit = -z / dz;
        const double r = std::hypot(x + t_exit * dx, y + t_exit * dy);
        t->histogram.add(r, w);
        if (t->dmfp) t->dmfp->add(r * inv_dmfp, w);
        t->exit_w += w;
        t->exit_w2 += w * w;
        break;
      }
      x += step * dx;
      y += step * dy;
      z = z_new;
      ++t->collisions;
      if (n + 1 >= s.max_collisions) {
        t->truncated_w += w;
        t->truncated_w2 += w * w;
        break;
      }
      w *= s.albedo;  // implicit capture: the survival probability of the collision
      if (w == 0.0) break;
      if (w < s.roulette_weight) {
        if (uniform_open(rng) >= s.roulette_survival) break;
        w /= s.roulette_survival;
      }
      // Isotropic phase function.
      const double c = 1.0 - 2.0 * uniform_open(rng);
      const double phi = two_pi * uniform_open(rng);
      const double st = std::sqrt(std::max(0.0, 1.0 - c * c));
      dx = st * std::cos(phi);
      dy = st * std::sin(phi);
      dz = c;
    }
  }
}

}  // namespace

SemiInfiniteMcResult simulate_semi_infinite(const SemiInfiniteMcSettings& s) {
  if (!(s.albedo >= 0.0 && s.albedo <= 1.0)) throw std::invalid_argument("albedo must lie in [0, 1]");
  if (!(s.mfp > 0.0) || !std::isfinite(s.mfp)) throw std::invalid_argument("mean free path must be positive");
  if (s.photons == 0) throw std::invalid_argument("photon count must be positive");
  for (const RadialBins* b : {&s.bins, s.dmfp_bins ? &*s.dmfp_bins : nullptr}) {
    if (b && !(b->r_min > 0.0 && b->r_max > b->r_min && b->count >= 1))
      throw std::invalid_argument("radial bins need 0 < r_min < r_max and at least one bin");
  }
  if (s.max_collisions < 1) throw std::invalid_argument("collision cap must be at least 1");
  if (!(s.roulette_survival > 0.0 && s.roulette_survival <= 1.0))
    throw std::invalid_argument("roulette survival must lie in (0, 1]");
  if (s.chunk_photons == 0) throw std::invalid_argument("chunk size must be positive");
  const double dmfp = diffuse_mean_free_path(s.albedo, 1.0 / s.mfp);
  if (s.dmfp_bins && !std::isfinite(dmfp)) throw std::invalid_argument("the dmfp histogram needs albedo < 1");

  const uint64_t chunks = (s.photons + s.chunk_photons - 1) / s.chunk_photons;
  std::vector<ChunkTally> tallies(chunks);
  tbb::parallel_for(uint64_t{0}, chunks, [&](uint64_t k) {
    ChunkTally& t = tallies[k];
    t.histogram = RadialHistogram(s.bins);
    if (s.dmfp_bins) t.dmfp = RadialHistogram(*s.dmfp_bins);
    const uint64_t first = k * s.chunk_photons;
    run_chunk(s, dmfp, k, std::min(s.chunk_photons, s.photons - first), &t);
  });

  SemiInfiniteMcResult r;
  r.settings = s;
  r.dmfp = dmfp;
  r.histogram = RadialHistogram(s.bins);
  if (s.dmfp_bins) r.dmfp_histogram = RadialHistogram(*s.dmfp_bins);
  double exit_w = 0.0, exit_w2 = 0.0, trunc_w = 0.0, trunc_w2 = 0.0;
  uint64_t collisions = 0;
  for (const ChunkTally& t : tallies) {  // chunk order: the sum does not depend on the schedule
    r.histogram.merge(t.histogram);
    if (r.dmfp_histogram) r.dmfp_histogram->merge(*t.dmfp);
    exit_w += t.exit_w;
    exit_w2 += t.exit_w2;
    trunc_w += t.truncated_w;
    trunc_w2 += t.truncated_w2;
    collisions += t.collisions;
  }
  const double n = static_cast<double>(s.photons);
  r.A = exit_w / n;
  r.A_se = standard_error(exit_w, exit_w2, n);
  r.truncated = trunc_w / n;
  r.truncated_se = standard_error(trunc_w, trunc_w2, n);
  r.below = r.histogram.below_w / n;
  r.above = r.histogram.above_w / n;
  r.mean_collisions = static_cast<double>(collisions) / n;
  return r;
}

std::vector<ProfileBin> SemiInfiniteMcResult::profile_of(const RadialHistogram& h) const {
  const double n = static_cast<double>(settings.photons);
  std::vector<ProfileBin> out;
  out.reserve(h.sum_w.size());
  for (int i = 0; i < h.bins.count; ++i) {
    ProfileBin b;
    b.r_lo = h.bins.edge(i);
    b.r_hi = h.bins.edge(i + 1);
    b.r_mid = std::sqrt(b.r_lo * b.r_hi);
    const double area = std::numbers::pi * (b.r_hi * b.r_hi - b.r_lo * b.r_lo);
    b.R = h.sum_w[i] / (n * area);
    b.R_se = standard_error(h.sum_w[i], h.sum_w2[i], n) / area;
    b.rR = b.r_mid * b.R;
    b.rR_se = b.r_mid * b.R_se;
    out.push_back(b);
  }
  return out;
}

}  // namespace kozu
