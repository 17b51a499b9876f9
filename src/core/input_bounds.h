// Bounds on the values a scene may give, shared by every parser (the scene loader, lights, shapes).
#pragma once

#include "core/json_reader.h"
#include "core/math.h"

#include <fmt/format.h>

#include <string>
#include <string_view>

namespace kozu {

// Radiometric bounds: values beyond them overflow float arithmetic on a path (radiance × throughput / pdf) or in
// a light's power, far beyond anything physical in any unit.
inline constexpr double kMaxRadiance = 1e30;
inline constexpr float kMaxLightPower = 1e30f;
// Positions and sizes: float arithmetic on them (squared distances, areas, error bounds) must stay finite, and
// Embree takes coordinates within ±1.8e18.
inline constexpr double kMaxCoordinate = 1e15;
inline constexpr Range kSizeRange{0.0, kMaxCoordinate, true, false};

inline bool within_bounds(const Vec3& p) { return double(max_component(glm::abs(p))) <= kMaxCoordinate; }
inline std::string bounds_message(const Vec3& p) {
  return fmt::format("coordinates must lie within ±{:g}, got ({:g}, {:g}, {:g})", kMaxCoordinate, p.x, p.y, p.z);
}
// A position: a vec3 within the coordinate bounds.
inline Vec3 get_point(const JsonObject& o, std::string_view key) {
  const Vec3 p = o.get_vec3(key);
  if (!within_bounds(p)) o.fail(key, bounds_message(p));
  return p;
}

}  // namespace kozu
