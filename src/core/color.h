// Linear RGB radiometric quantities (Rec. 709 primaries, the working space of kozu).
#pragma once

#include "core/math.h"

#include <cmath>

namespace kozu {

using Rgb = glm::vec3;

// Relative luminance Y of linear Rec. 709 RGB.
inline float luminance(const Rgb& c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }

inline bool is_black(const Rgb& c) { return c.r == 0.0f && c.g == 0.0f && c.b == 0.0f; }

// The sRGB transfer function's inverse (IEC 61966-2-1): an encoded value in [0, 1] to linear.
inline float srgb_to_linear(float v) { return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f); }

}  // namespace kozu
