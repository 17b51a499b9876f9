#include "bssrdf/normalized_diffusion.h"

#include "core/math.h"

#include <cmath>

namespace kozu {

double normalized_diffusion::scale(SubsurfaceParameterization p, double A) {
  switch (p) {
    case SubsurfaceParameterization::Searchlight: {
      const double e = std::abs(A - 0.8);
      return 1.85 - A + 7.0 * e * e * e;  // eq. (5)
    }
    case SubsurfaceParameterization::Diffuse:
      return 1.9 - A + 3.5 * (A - 0.8) * (A - 0.8);  // eq. (6)
    case SubsurfaceParameterization::Dmfp: {
      const double e = (A - 0.33) * (A - 0.33);
      return 3.5 + 100.0 * e * e;  // eq. (8)
    }
  }
  return 1.0;
}

NormalizedDiffusion NormalizedDiffusion::from_length(SubsurfaceParameterization p, float A, float length) {
  return NormalizedDiffusion(A, static_cast<float>(length / normalized_diffusion::scale(p, A)));
}

float NormalizedDiffusion::eval(float r) const {
  if (!(r > 0.0f)) return 0.0f;  // the 1/r peak at 0 is integrable; a zero radius has no area
  return A_ * (std::exp(-r / d_) + std::exp(-r / (3.0f * d_))) / (8.0f * kPi * d_ * r);  // eq. (2)
}

float NormalizedDiffusion::pdf(float r) const {
  if (r < 0.0f) return 0.0f;
  return (std::exp(-r / d_) + std::exp(-r / (3.0f * d_))) / (4.0f * d_);
}

double NormalizedDiffusion::cdf(double r) const {
  if (r <= 0.0) return 0.0;
  const double d = d_;
  return 1.0 - 0.25 * std::exp(-r / d) - 0.75 * std::exp(-r / (3.0 * d));  // eq. (11)
}

float NormalizedDiffusion::sample_closed_form(float u) const {
  const double v = 1.0 - static_cast<double>(u);
  if (!(v > 0.0)) return kInfinity;
  const double x = 2.0 * std::sinh(std::asinh(2.0 * v) / 3.0);  // root of x³ + 3x = 4v
  return static_cast<float>(-3.0 * d_ * std::log(x));
}

float NormalizedDiffusion::sample(float u, int* iterations) const {
  const double v = 1.0 - static_cast<double>(u);
  if (!(v > 0.0)) return kInfinity;
  const double c = 4.0 * v;
  double x = std::min(1.0, c / 3.0);
  int k = 0;
  for (; k < 16; ++k) {
    const double step = (x * (x * x + 3.0) - c) / (3.0 * (x * x + 1.0));
    x -= step;
    if (step <= 1e-15 * x) break;  // the iterates decrease monotonically onto the root
  }
  if (iterations) *iterations = k + 1;
  return static_cast<float>(-3.0 * d_ * std::log(x));
}

}  // namespace kozu
