// Display transforms for 8-bit outputs (.png/.jpg); .exr output is always linear and untouched.
//
//   aces     (default) exposure, then the ACES RRT+ODT fit of S. Hill ("BakingLab", 2016):
//            sRGB -> ACES AP1-ish input matrix, the rational curve
//            (v (v + 0.0245786) - 0.000090537) / (v (0.983729 v + 0.4329510) + 0.238081),
//            output matrix back to linear sRGB; then the sRGB transfer function.
//   neutral  Khronos PBR Neutral (2024): keeps base colours exact up to 0.8, then compresses
//            highlights with a hyperbola and desaturates towards white.
//   agx      T. Sobotka's AgX (github.com/sobotka/AgX; Blender 4.x's default "AgX" view) in B. Wrensch's closed
//            form ("Minimal AgX Implementation", iolite-engine.com, 2023): the inset matrix on linear Rec.709;
//            log2 over [-12.47393, 4.026069] EV (0.18 grey at 10 of the 16.5 stops: x = 0.606), the sigmoid as
//            Wrensch's 6th-order polynomial fit (15.5x^6 - 40.14x^5 + 31.96x^4 - 6.868x^3 + 0.4298x^2
//            + 0.1191x - 0.00232); the outset (inverse inset) matrix; the result, display-encoded with a 2.2
//            power, decoded to linear (clamped to [0, 1]) for the writer's sRGB encoding. No "look" (punchy,
//            golden) is applied. 0.18 grey comes out at 0.4967 display-encoded (the fit at x = 0.606), 0.2145
//            linear after the 2.2 decode, so about code 127 of 255 in the sRGB PNG; highlights desaturate to white.
//            Not Blender's pixels: Blender's OCIO config applies the exact sigmoid (a LUT) and an outset with a
//            rotation; this is the published approximation, not compared with Blender's output here (nor its
//            difference measured). Past display white a single channel pushed further dips by up to 0.35 % as the
//            inset leaks it into the others (AgX's path to white); grey is monotone to white (0.9969).
//   clamp    exposure, clamp to [0, 1], sRGB transfer function.
// Quantisation to 8 bits adds a triangular dither of one code value to avoid banding; the dither
// is a hash of the pixel position, so outputs are deterministic.
#pragma once

#include "core/color.h"

#include <string>

namespace kozu {

struct ToneMap {
  enum class Curve { Aces, Neutral, Agx, Clamp };
  Curve curve = Curve::Aces;
  float exposure = 0.0f;  // stops: the image is multiplied by 2^exposure before the curve

  static Curve parse(const std::string& name);  // "aces" | "neutral" | "agx" | "clamp"
  // Linear scene-referred RGB -> display-referred linear RGB in [0, 1].
  Rgb apply(const Rgb& c) const;
};

float srgb_encode(float linear);  // IEC 61966-2-1 transfer function, input clamped to [0, 1]

}  // namespace kozu
