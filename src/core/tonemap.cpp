#include "core/tonemap.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace kozu {

namespace {

Rgb aces_hill(Rgb c) {
  // Rows of the matrices from S. Hill's fit (sRGB primaries, D65).
  const Rgb in(0.59719f * c.r + 0.35458f * c.g + 0.04823f * c.b, 0.07600f * c.r + 0.90834f * c.g + 0.01566f * c.b,
               0.02840f * c.r + 0.13383f * c.g + 0.83777f * c.b);
  auto curve = [](float v) {
    return (v * (v + 0.0245786f) - 0.000090537f) / (v * (0.983729f * v + 0.4329510f) + 0.238081f);
  };
  const Rgb t(curve(in.r), curve(in.g), curve(in.b));
  const Rgb out(1.60475f * t.r - 0.53108f * t.g - 0.07367f * t.b, -0.10208f * t.r + 1.10813f * t.g - 0.00605f * t.b,
                -0.00327f * t.r - 0.07276f * t.g + 1.07602f * t.b);
  return glm::clamp(out, Rgb(0.0f), Rgb(1.0f));
}

Rgb khronos_neutral(Rgb c) {
  constexpr float kStart = 0.8f - 0.04f;
  constexpr float kDesat = 0.15f;
  const float x = std::min(c.r, std::min(c.g, c.b));
  const float offset = x < 0.08f ? x - 6.25f * x * x : 0.04f;
  c -= Rgb(offset);
  const float peak = max_component(c);
  if (peak < kStart) return glm::clamp(c, Rgb(0.0f), Rgb(1.0f));
  const float d = 1.0f - kStart;
  const float new_peak = 1.0f - d * d / (peak + d - kStart);
  c *= new_peak / peak;
  const float g = 1.0f - 1.0f / (kDesat * (peak - new_peak) + 1.0f);
  return glm::clamp(glm::mix(c, Rgb(new_peak), g), Rgb(0.0f), Rgb(1.0f));
}

// AgX (T. Sobotka, github.com/sobotka/AgX; Blender's default view transform since 4.0) in the closed form of
// B. Wrensch, "Minimal AgX Implementation" (iolite-engine.com/blog_posts/minimal_agx_implementation, 2023), the
// formulation most real-time ports cite: core/tonemap.h lists the steps.
Rgb agx(Rgb c) {
  // In double: the polynomial's terms (up to 40 x^5) cancel to values near 1, and in float that rounding (1e-5
  // near white) made the curve step back while its input rose.
  const double r = c.r, g = c.g, b = c.b;
  // Inset: linear Rec.709 towards the achromatic axis (Wrensch's agxMat, written as rows).
  const double in[3] = {0.842479062253094 * r + 0.0784335999999992 * g + 0.0792237451477643 * b,
                        0.0423282422610123 * r + 0.878468636469772 * g + 0.0791661274605434 * b,
                        0.0423756549057051 * r + 0.0784336000000000 * g + 0.879142973793104 * b};
  // Log2 encoding over [-12.47393, 4.026069] EV around 0.18 (-2.47393 EV), normalized to [0, 1].
  constexpr double kMinEv = -12.47393, kMaxEv = 4.026069;
  double t[3];
  for (int i = 0; i < 3; ++i) {
    const double e = in[i] > 0.0 ? std::clamp(std::log2(in[i]), kMinEv, kMaxEv) : kMinEv;
    const double x = (e - kMinEv) / (kMaxEv - kMinEv);
    // Wrensch's 6th-order polynomial fit of AgX's default sigmoid (agxDefaultContrastApprox).
    const double x2 = x * x, x4 = x2 * x2;
    t[i] = 15.5 * x4 * x2 - 40.14 * x4 * x + 31.96 * x4 - 6.868 * x2 * x + 0.4298 * x2 + 0.1191 * x - 0.00232;
  }
  // Outset (agxMatInv, rows), then the curve's display encoding (a 2.2 power) undone into linear light: the
  // writer applies the sRGB encoding, as for the other curves. The fit dips to -0.00232 at black: clamped.
  const double out[3] = {1.19687900512017 * t[0] - 0.0980208811401368 * t[1] - 0.0990297440797205 * t[2],
                         -0.0528968517574562 * t[0] + 1.15190312990417 * t[1] - 0.0989611768448433 * t[2],
                         -0.0529716355144438 * t[0] - 0.0980434501171241 * t[1] + 1.15107367264116 * t[2]};
  Rgb lin;
  for (int i = 0; i < 3; ++i) lin[i] = static_cast<float>(std::pow(std::clamp(out[i], 0.0, 1.0), 2.2));
  return lin;
}

}  // namespace

ToneMap::Curve ToneMap::parse(const std::string& name) {
  if (name == "aces") return Curve::Aces;
  if (name == "neutral") return Curve::Neutral;
  if (name == "agx") return Curve::Agx;
  if (name == "clamp") return Curve::Clamp;
  throw std::invalid_argument("unknown tone map '" + name + "' (expected aces, neutral, agx or clamp)");
}

Rgb ToneMap::apply(const Rgb& c_in) const {
  // Every curve is display white long before 10^6 (ACES within 10^-6 of its asymptote); clamping there keeps the
  // curves' products finite for any input and exposure, and sends NaN to 0.
  constexpr float kWhite = 1e6f;
  const float scale = std::exp2(exposure);
  Rgb c;
  for (int i = 0; i < 3; ++i) {
    const float v = c_in[i] * scale;
    c[i] = v > 0.0f ? std::min(v, kWhite) : 0.0f;
  }
  switch (curve) {
    case Curve::Aces:
      return aces_hill(c);
    case Curve::Neutral:
      return khronos_neutral(c);
    case Curve::Agx:
      return agx(c);
    case Curve::Clamp:
      return glm::clamp(c, Rgb(0.0f), Rgb(1.0f));
  }
  return c;
}

float srgb_encode(float v) {
  v = std::clamp(v, 0.0f, 1.0f);
  return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

}  // namespace kozu
