#include "lights/light_power.h"

#include "core/input_bounds.h"

#include <fmt/format.h>

namespace kozu {

LightStrength read_strength(const JsonObject& desc, std::string_view key, std::optional<Rgb> def) {
  const bool has_key = desc.has(key), has_power = desc.has("power");
  if (has_key && has_power) desc.fail("power", fmt::format("give either '{}' or 'power' (watts), not both", key));
  if (has_power) return {desc.get_rgb("power", {}, Range::closed(0.0, double(kMaxLightPower))), true};
  if (!has_key && !def) desc.fail(fmt::format("missing required key '{}' (or 'power' in watts)", key));
  return {desc.get_rgb(key, def), false};
}

void refuse_power(const JsonObject& desc, std::string_view use_instead, std::string_view why) {
  if (desc.has("power"))
    desc.fail("power", fmt::format("this light takes no 'power': {}; give '{}'", why, use_instead));
}

Rgb power_to(const JsonObject& desc, const Rgb& power, double per_unit, std::string_view what) {
  const double peak = double(max_component(power)) / per_unit;
  if (!(peak <= kMaxRadiance))
    desc.fail("power", fmt::format("{:g} W needs {} = {:.3g}, beyond kozu's range (at most {:g})",
                                   double(max_component(power)), what, peak, kMaxRadiance));
  return Rgb(Vec3d(power) / per_unit);
}

}  // namespace kozu
