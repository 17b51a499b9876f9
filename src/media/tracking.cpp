#include "media/tracking.h"

#include "core/rng.h"

#include <algorithm>
#include <cmath>

namespace kozu {

namespace {
// How far ratio tracking raises a segment's majorant at most (Medium::ratio_tracking_min_collisions): a bound on the
// lookups it adds where a segment is short.
constexpr float kMaxMajorantRaise = 8.0f;

// Walks the tentative collisions of ray over [0, t_max] against the medium's piecewise-constant majorants and calls
// f(t, majorant, properties at t); f returns false to stop. Returns false when the path's budget ran out before the
// walk ended. With raise (ratio tracking), a segment whose majorant expects fewer than the medium's
// ratio_tracking_min_collisions() collisions takes a higher one, up to kMaxMajorantRaise times its own. The optical
// depth to the next tentative collision, τ ~ Exp(1), is drawn once and spent across segments (σ̄ (tb − ta) each):
// the same distribution as a fresh draw per segment (the exponential is memoryless), without a draw and a logarithm
// per cell crossed; each step of the budget is then one lookup.
template <class F>
bool for_each_tentative_collision(const Medium& medium, const Ray& ray, float t_max, WalkUniforms& u, PathBudget& budget,
                                  const RayCone& cone, F&& f, bool raise = false) {
  bool within_budget = true, go_on = true;
  float tau = -1.0f;  // the optical depth left to the next tentative collision; < 0: not drawn yet
  for (float ta = 0.0f; go_on && within_budget && ta < t_max;) {
    // One level of detail per part of the ray: the one that serves the cone's width where the part starts, or, where
    // the part starts on a level's boundary (the end of the last part), the one that serves its middle: the width
    // there rounds to either side, and the level just left would take the whole part (a converging cone walked its
    // coarse level from its fine level's start to the far side of its focus).
    Medium::Lod lod = medium.level_for(cone.width_at(ta));
    float tb = std::min(t_max, cone.leaves(ta, lod.width_lo, lod.width_hi));
    if (std::isfinite(tb)) {
      const Medium::Lod inside = medium.level_for(cone.width_at(0.5f * (ta + tb)));
      if (inside.medium != lod.medium) {
        lod = inside;
        tb = std::min(t_max, cone.leaves(ta, lod.width_lo, lod.width_hi));
      }
    }
    const Medium& m = *lod.medium;
    const float min_collisions = raise ? m.ratio_tracking_min_collisions() : 0.0f;
    for_each_majorant(m, ray.o, ray.d, ta, tb, [&](float t0, float t1, float majorant) {
      if (!(majorant > 0.0f)) return true;
      if (min_collisions > 0.0f)
        majorant = std::max(majorant, std::min(min_collisions / (t1 - t0), kMaxMajorantRaise * majorant));
      float t = t0;
      for (;;) {
        // 1 − u is exact for u on the 2⁻²⁴ lattice of next_float and ≥ 2⁻²⁴, and logf is much cheaper than log1pf.
        if (tau < 0.0f) tau = -std::log(1.0f - u.next());
        const float dt = tau / majorant;
        if (!(t + dt < t1)) {  // no collision in this segment: spend its optical depth
          tau -= (t1 - t) * majorant;
          return true;
        }
        t += dt;
        tau = -1.0f;
        if (!budget.step()) return within_budget = false;
        // σt(ω) = ρ σ(ω), σs(ω) = α ρ σ(ω) along the ray's direction: Heitz et al. 2015 eqs. (2)–(3) (microflake
        // media).
        if (!f(t, majorant, m.properties(ray.o + t * ray.d, ray.d))) return go_on = false;
      }
    });
    ta = tb;
  }
  return within_budget;
}
}  // namespace

bool sample_free_flight(const Medium& medium, const Ray& ray, float t_max, WalkUniforms u, Rgb& beta, float* t_out,
                        PathBudget& budget, const RayCone& cone) {
  bool scattered = false;
  const bool complete = for_each_tentative_collision(medium, ray, t_max, u, budget, cone, [&](float t, float majorant,
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
    if (u.next() < p_s) {
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

Rgb ratio_tracking(const Medium& medium, const Ray& ray, float t_max, WalkUniforms u, PathBudget& budget,
                   const RayCone& cone) {
  Rgb T(1.0f);
  const bool complete = for_each_tentative_collision(medium, ray, t_max, u, budget, cone, [&](float, float majorant,
                                                                                          const MediumProperties& mp) {
    T *= max(Rgb(0.0f), Rgb(1.0f) - mp.sigma_t / majorant);  // ratio tracking (Novák et al. 2014): T = Π (1 − σt/σ̄)
    // Russian roulette once every channel is below 0.1.
    const float m = max_component(T);
    if (m < 0.1f) {
      if (u.next() >= m) {
        T = Rgb(0.0f);
        return false;
      }
      T /= m;
    }
    return true;
  }, /*raise=*/true);
  return complete ? T : Rgb(0.0f);
}

}  // namespace kozu
