#include "materials/microfacet.h"

#include <stdexcept>
#include <string>

namespace kozu {

float erf_inv(float x) {
  // ±1 map to ±erf_inv(1 − 2^-24) ≈ ±3.83, finite. (Clamping to 1 − 1e-7 instead, which rounds to 1 − 2^-23,
  // answered 3.74 for the largest float below 1, whose inverse is 3.83.)
  x = std::clamp(x, -kOneMinusEpsilon, kOneMinusEpsilon);
  // Giles 2010, single-precision rational approximation (constants from the paper).
  float w = -std::log((1.0f - x) * (1.0f + x));
  float p;
  if (w < 5.0f) {
    w -= 2.5f;
    p = 2.81022636e-08f;
    p = 3.43273939e-07f + p * w;
    p = -3.5233877e-06f + p * w;
    p = -4.39150654e-06f + p * w;
    p = 0.00021858087f + p * w;
    p = -0.00125372503f + p * w;
    p = -0.00417768164f + p * w;
    p = 0.246640727f + p * w;
    p = 1.50140941f + p * w;
  } else {
    w = std::sqrt(w) - 3.0f;
    p = -0.000200214257f;
    p = 0.000100950558f + p * w;
    p = 0.00134934322f + p * w;
    p = -0.00367342844f + p * w;
    p = 0.00573950773f + p * w;
    p = -0.0076224613f + p * w;
    p = 0.00943887047f + p * w;
    p = 1.00167406f + p * w;
    p = 2.83297682f + p * w;
  }
  // One Newton step on erf(y) = x in double removes the approximation's last bits of error.
  const double y = static_cast<double>(p) * x;
  const double err = std::erf(y) - x;
  return static_cast<float>(y - err / (1.1283791670955126 * std::exp(-y * y)));
}

Vec2 MicrofacetDistribution::sample_beckmann_slopes(const Vec3& ws, const Vec2& u) {
  const float sin_theta = std::sqrt(std::max(0.0f, ws.x * ws.x + ws.y * ws.y));
  // The stretched Beckmann P22 = exp(−x̃² − ỹ²)/π (ushiostarfish 2018, slope space) is separable: ỹ is N(0, 1/2),
  // independent of the x slope; at normal incidence x̃ is too (plain P22).
  const float y_slope = erf_inv(2.0f * u.y - 1.0f);
  if (sin_theta < 1e-5f) return Vec2(erf_inv(2.0f * u.x - 1.0f), y_slope);

  // x slope in the incidence plane: density ∝ (c − x) exp(−x²) on x < c, c = cot θ. Its CDF is
  // C(x) = c (√π/2)(1 + erf x) + exp(−x²)/2; solve C(x) = u·C(c) by Newton steps kept inside a
  // bisection bracket. Slopes beyond ±6 carry a mass below exp(−36): the bracket stops there.
  const double c = static_cast<double>(ws.z) / sin_theta;
  const double half_sqrt_pi = 0.8862269254527580;
  auto cdf = [&](double x) { return c * half_sqrt_pi * (1.0 + std::erf(x)) + 0.5 * std::exp(-x * x); };  // C(x)
  // (A downward ray, c < -6, only arises in the multiple-scattering walk: keep the bracket non-empty.)
  double lo = std::min(-6.0, c - 6.0), hi = std::min(c, 6.0);
  const double total = cdf(c);
  const double target = static_cast<double>(u.x) * total;
  const double tolerance = 1e-7 * total;
  double x = std::clamp(static_cast<double>(erf_inv(2.0f * u.x - 1.0f)), lo, hi);
  for (int i = 0; i < 40; ++i) {
    const double f = cdf(x) - target;
    if (std::abs(f) <= tolerance) break;
    if (f > 0.0)
      hi = x;
    else
      lo = x;
    const double density =
        (c - x) * std::exp(-x * x);  // C'(x): visible slopes ∝ (cot θ − x̃) P2(x̃) (ushiostarfish 2018)
    double next = density > 0.0 ? x - f / density : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    x = next;
  }
  // Rotate from the incidence plane to ws's azimuth.
  const float cos_phi = ws.x / sin_theta, sin_phi = ws.y / sin_theta;
  const float xs = static_cast<float>(x);
  return Vec2(cos_phi * xs - sin_phi * y_slope, sin_phi * xs + cos_phi * y_slope);
}

MicrofacetType microfacet_type_from_string(std::string_view s) {
  if (s == "ggx") return MicrofacetType::GGX;
  if (s == "beckmann") return MicrofacetType::Beckmann;
  throw std::invalid_argument("unknown microfacet distribution '" + std::string(s) + "'");
}

}  // namespace kozu
