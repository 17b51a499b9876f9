#include "render/denoiser_ensemble.h"

#include "render/denoiser.h"
#include "render/feature_regression.h"

#include <algorithm>
#include <cmath>

namespace kozu {

std::vector<float> denoise_ensemble(const Film& film, const VisibleEmission* emission,
                                    const std::function<bool()>& expired) {
  std::vector<float> risk_nl, risk_reg;
  std::vector<float> out = denoise(film, {}, emission, expired, &risk_nl);
  if (expired && expired()) return out;
  const std::vector<float> other = denoise_regression(film, {}, emission, expired, &risk_reg);
  for (size_t p = 0; p < risk_nl.size() && p < risk_reg.size() && 3 * p + 2 < other.size(); ++p) {
    // The estimates are noisy and may be negative: each is floored at a hundredth of the two's magnitudes (and at
    // 1e-12); a risk that is not a number takes the floor, so every weight is finite and in [0, 1].
    const float floor = std::max(1e-12f, 0.01f * (std::abs(risk_nl[p]) + std::abs(risk_reg[p])));
    const float r_nl = risk_nl[p] > floor ? risk_nl[p] : floor, r_reg = risk_reg[p] > floor ? risk_reg[p] : floor;
    float w_nl = r_reg / (r_nl + r_reg);
    if (!std::isfinite(w_nl)) w_nl = 0.5f;
    for (size_t c = 3 * p; c < 3 * p + 3; ++c) out[c] = w_nl * out[c] + (1.0f - w_nl) * other[c];
  }
  return out;
}

}  // namespace kozu
