#include "textures/checker_texture.h"

#include <algorithm>
#include <cmath>

namespace kozu {

namespace {

// The square wave S: +1 on even cells, −1 on odd ones.
double square_wave(double x) { return std::fmod(std::floor(x), 2.0) == 0.0 ? 1.0 : -1.0; }

// T(x) = ∫₀ˣ S: a triangle wave of period 2 (checker_texture.h).
double triangle_wave(double x) {
  const double t = x - 2.0 * std::floor(0.5 * x);
  return t <= 1.0 ? t : 2.0 - t;
}

// The mean of S over [x0, x1]; the point value when the interval is empty (or too narrow for doubles).
double mean_square_wave(double x0, double x1) {
  const double w = x1 - x0;
  if (!(w > 1e-9)) return square_wave(0.5 * (x0 + x1));
  return (triangle_wave(x1) - triangle_wave(x0)) / w;
}

}  // namespace

double CheckerTexture::b_fraction(double x0, double x1, double y0, double y1) {
  return 0.5 * (1.0 - mean_square_wave(x0, x1) * mean_square_wave(y0, y1));
}

Rgb CheckerTexture::eval(const TextureQuery& q) const {
  const double x = double(scale_.x) * q.uv.x, y = double(scale_.y) * q.uv.y;
  const double hx = double(scale_.x) * std::max(std::abs(q.duvdx.x), std::abs(q.duvdy.x));
  const double hy = double(scale_.y) * std::max(std::abs(q.duvdx.y), std::abs(q.duvdy.y));
  const float wb = static_cast<float>(b_fraction(x - hx, x + hx, y - hy, y + hy));
  return (1.0f - wb) * a_ + wb * b_;
}

}  // namespace kozu
