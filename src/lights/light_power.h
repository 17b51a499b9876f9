// Light power in watts: the alternative to a light's intensity, radiance or emission (docs/lights.md "Light power
// in watts"). Each light converts a power Phi (W, per RGB channel) to the quantity it renders with by dividing by
// its power per unit of that quantity, the same factor Light::power() multiplies by:
//   point           I = Phi / (4 pi)                                   (x the profile's integral, lights/ies_profile.h)
//   spot            I = Phi / (2 pi (1 - (cos falloff + cos cone) / 2))
//   area (shape)    L = Phi / (pi A)        one-sided;  Phi / (2 pi A)  two-sided
// Directional and environment lights have no power of their own: theirs is counted over the scene's bounding disk
// (docs/scene-format.md "Light selection"), so they refuse "power".
#pragma once

#include "core/json_reader.h"

#include <optional>
#include <string_view>

namespace kozu {

// How the scene gave a light's strength: the value of the light's own key, or a power in watts.
struct LightStrength {
  Rgb value{0.0f};
  bool is_power = false;
};

// Reads exactly one of `key` (e.g. "intensity") and "power" (rgb or a number, >= 0, W). Giving both is an error that
// names both keys; giving neither takes def, or is an error naming both when there is none.
LightStrength read_strength(const JsonObject& desc, std::string_view key, std::optional<Rgb> def = {});

// For lights whose power is not a property of the light alone: "power" is an error that says which key to give.
void refuse_power(const JsonObject& desc, std::string_view use_instead, std::string_view why);

// value / per_unit, refused (naming "power") when the quotient is beyond kozu's radiance range; per_unit > 0.
Rgb power_to(const JsonObject& desc, const Rgb& power, double per_unit, std::string_view what);

}  // namespace kozu
