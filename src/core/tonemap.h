// Display transforms for 8-bit outputs (.png/.jpg); .exr output is always linear and untouched.
//
//   aces     (default) exposure, then the ACES RRT+ODT fit of S. Hill ("BakingLab", 2016):
//            sRGB -> ACES AP1-ish input matrix, the rational curve
//            (v (v + 0.0245786) - 0.000090537) / (v (0.983729 v + 0.4329510) + 0.238081),
//            output matrix back to linear sRGB; then the sRGB transfer function.
//   neutral  Khronos PBR Neutral (2024): keeps base colours exact up to 0.8, then compresses
//            highlights with a hyperbola and desaturates towards white.
//   clamp    exposure, clamp to [0, 1], sRGB transfer function.
// Quantisation to 8 bits adds a triangular dither of one code value to avoid banding; the dither
// is a hash of the pixel position, so outputs are deterministic.
#pragma once

#include "core/color.h"

#include <string>

namespace kozu {

struct ToneMap {
  enum class Curve { Aces, Neutral, Clamp };
  Curve curve = Curve::Aces;
  float exposure = 0.0f;  // stops: the image is multiplied by 2^exposure before the curve

  static Curve parse(const std::string& name);  // "aces" | "neutral" | "clamp"
  // Linear scene-referred RGB -> display-referred linear RGB in [0, 1].
  Rgb apply(const Rgb& c) const;
};

float srgb_encode(float linear);  // IEC 61966-2-1 transfer function, input clamped to [0, 1]

}  // namespace kozu
