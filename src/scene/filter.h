// Pixel reconstruction filters, applied by filter importance sampling (Ernst et al. 2006): each
// camera sample's offset from the pixel centre is drawn from the filter and the sample counts with
// weight 1 in its own pixel only. This keeps every pixel an independent, unbiased average of its
// own samples, which progressive and time-limited rendering need.
//
//   box       offsets uniform in [-0.5, 0.5]^2
//   tent      separable triangle of radius 1
//   gaussian  separable Gaussian, sigma 0.5, truncated at radius 1.5 (3 sigma)
#pragma once

#include "core/math.h"

#include <string>
#include <vector>

namespace kozu {

class PixelFilter {
 public:
  enum class Type { Box, Tent, Gaussian };
  explicit PixelFilter(Type type = Type::Gaussian);
  static Type parse(const std::string& name);  // "box" | "tent" | "gaussian"
  static const char* name(Type type);

  // Offset from the pixel centre, in pixels.
  Vec2 sample(const Vec2& u) const { return Vec2(sample_1d(u.x), sample_1d(u.y)); }
  float sample_1d(float u) const;
  Type type() const { return type_; }

 private:
  Type type_;
  float radius_ = 0.5f;
  std::vector<float> inverse_cdf_;  // tabulated inverse CDF for the Gaussian
};

}  // namespace kozu
