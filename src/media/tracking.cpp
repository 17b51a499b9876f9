#include "media/tracking.h"

#include "core/rng.h"

#include <cmath>

namespace kozu {

namespace {
// Walks the tentative collisions of ray over [0, t_max] against the medium's majorants (exponential steps of
// rate σ̄ within each segment) and calls f(t, majorant, properties at t); f returns false to stop. Returns false
// when the path's budget ran out before the walk ended.
template <class F>
bool for_each_tentative_collision(const Medium& medium, const Ray& ray, float t_max, Pcg32& rng, PathBudget& budget,
                                  F&& f) {
  bool within_budget = true;
  for_each_majorant(medium, ray.o, ray.d, 0.0f, t_max, [&](float t0, float t1, float majorant) {
    if (!(majorant > 0.0f)) return true;
    float t = t0;
    for (;;) {
      if (!budget.step()) return within_budget = false;
      // Free path of density σ̄ exp(−σ̄ t) against the majorant σ̄ (delta tracking's tentative collisions).
      // 1 − u is exact for u on the 2⁻²⁴ lattice of next_float and ≥ 2⁻²⁴, and logf is much cheaper than log1pf.
      t -= std::log(1.0f - rng.next_float()) / majorant;
      if (t >= t1) return true;
      // σt(ω) = ρ σ(ω), σs(ω) = α ρ σ(ω) along the ray's direction: Heitz et al. 2015 eqs. (2)–(3) (microflake media).
      if (!f(t, majorant, medium.properties(ray.o + t * ray.d, ray.d))) return false;
    }
  });
  return within_budget;
}
}  // namespace

bool sample_free_flight(const Medium& medium, const Ray& ray, float t_max, Pcg32& rng, Rgb& beta, float* t_out,
                        PathBudget& budget) {
  bool scattered = false;
  const bool complete = for_each_tentative_collision(medium, ray, t_max, rng, budget, [&](float t, float majorant,
                                                                                          const MediumProperties& mp) {
    // Spectral tracking (Kutz et al. 2017): null coefficient σn = σ̄ − σt; a real scattering or a null event with
    // probabilities proportional to the throughput-weighted σs and σn, and beta times σ_x / (σ̄ P_x).
    const Rgb sigma_n = max(Rgb(0.0f), Rgb(majorant) - mp.sigma_t);
    const float ws = (beta.r * mp.sigma_s.r + beta.g * mp.sigma_s.g + beta.b * mp.sigma_s.b);
    const float wn = (beta.r * sigma_n.r + beta.g * sigma_n.g + beta.b * sigma_n.b);
    if (!(ws + wn > 0.0f)) {
      beta = Rgb(0.0f);  // everything left is absorbed here
      return false;
    }
    const float p_s = ws / (ws + wn);
    if (rng.next_float() < p_s) {
      beta *= mp.sigma_s / (majorant * p_s);
      *t_out = t;
      scattered = true;
      return false;
    }
    beta *= sigma_n / (majorant * (1.0f - p_s));
    return true;
  });
  if (!complete) beta = Rgb(0.0f);
  return scattered;
}

Rgb ratio_tracking(const Medium& medium, const Ray& ray, float t_max, Pcg32& rng, PathBudget& budget) {
  Rgb T(1.0f);
  const bool complete = for_each_tentative_collision(medium, ray, t_max, rng, budget, [&](float, float majorant,
                                                                                          const MediumProperties& mp) {
    T *= max(Rgb(0.0f), Rgb(1.0f) - mp.sigma_t / majorant);  // ratio tracking (Novák et al. 2014): T = Π (1 − σt/σ̄)
    // Russian roulette once every channel is below 0.1.
    const float m = max_component(T);
    if (m < 0.1f) {
      if (rng.next_float() >= m) {
        T = Rgb(0.0f);
        return false;
      }
      T /= m;
    }
    return true;
  });
  return complete ? T : Rgb(0.0f);
}

}  // namespace kozu
