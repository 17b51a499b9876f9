#include "core/tonemap.h"

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

}  // namespace

ToneMap::Curve ToneMap::parse(const std::string& name) {
  if (name == "aces") return Curve::Aces;
  if (name == "neutral") return Curve::Neutral;
  if (name == "clamp") return Curve::Clamp;
  throw std::invalid_argument("unknown tone map '" + name + "' (expected aces, neutral or clamp)");
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
