#include "media/homogeneous_flight.h"

#include <cmath>
#include <limits>

namespace kozu {

HomogeneousFlight::HomogeneousFlight(const Rgb& sigma_t, const Rgb& beta) : sigma_t_(sigma_t) {
  const Rgb b = max(beta, Rgb(0.0f));
  const float sum = b.r + b.g + b.b;
  // A throughput of 0 (or NaN) everywhere: any choice is as good, and the caller's weights are 0 anyway.
  q_ = sum > 0.0f && std::isfinite(sum) ? b / sum : Rgb(1.0f / 3.0f);
}

float HomogeneousFlight::sample(float u_channel, float u) const {
  const float s = u_channel < q_.r ? sigma_t_.r : u_channel < q_.r + q_.g ? sigma_t_.g : sigma_t_.b;
  if (!(s > 0.0f)) return std::numeric_limits<float>::infinity();
  // 1 − u is exact for u on next_float's 2⁻²⁴ lattice and ≥ 2⁻²⁴ (media/tracking.cpp).
  return -std::log(1.0f - u) / s;
}

Rgb homogeneous_transmittance(const Rgb& sigma_t, float t) {
  // A grey medium's three channels are one exp (the same bits as three).
  if (sigma_t.r == sigma_t.g && sigma_t.g == sigma_t.b)
    return Rgb(sigma_t.r > 0.0f ? std::exp(-sigma_t.r * t) : 1.0f);
  Rgb T;
  for (int c = 0; c < 3; ++c) T[c] = sigma_t[c] > 0.0f ? std::exp(-sigma_t[c] * t) : 1.0f;
  return T;
}

float HomogeneousFlight::pdf_of(const Rgb& T) const {
  return q_.r * sigma_t_.r * T.r + q_.g * sigma_t_.g * T.g + q_.b * sigma_t_.b * T.b;
}

float HomogeneousFlight::pass_probability_of(const Rgb& T) const { return q_.r * T.r + q_.g * T.g + q_.b * T.b; }

}  // namespace kozu
