#include "lights/spot.h"

#include "core/input_bounds.h"
#include "lights/light_power.h"
#include "lights/point.h"

namespace kozu {

SpotLight::SpotLight(const Vec3& position, const Vec3& direction, const Rgb& intensity, float cone_deg,
                     float falloff_deg, std::shared_ptr<const IesProfile> profile)
    : position_(position),
      frame_(luminaire_frame(glm::normalize(direction))),
      intensity_(intensity),
      cos_cone_(std::cos(glm::radians(cone_deg))),
      cos_falloff_(std::cos(glm::radians(falloff_deg))),
      cone_deg_(cone_deg),
      falloff_deg_(falloff_deg),
      profile_(std::move(profile)),
      solid_angle_(solid_angle()) {}

float SpotLight::falloff(float cos_theta) const {
  if (cos_theta >= cos_falloff_) return 1.0f;
  if (cos_theta <= cos_cone_) return 0.0f;
  const float t = (cos_theta - cos_cone_) / (cos_falloff_ - cos_cone_);
  return t * t * (3.0f - 2.0f * t);  // spot.h: I(theta) = I smoothstep(cos cone, cos falloff, cos theta)
}

LightSample SpotLight::sample(const LightSampleContext& ctx, const Vec2&) const {
  LightSample ls = sample_point_emitter(position_, intensity_, ctx);
  if (!ls.valid()) return ls;
  ls.radiance *= falloff(glm::dot(-ls.wi, frame_.n));
  if (profile_) ls.radiance *= profile_->eval(frame_.to_local(-ls.wi));
  return ls;
}

double SpotLight::solid_angle() const {
  const double cos_cone = std::cos(glm::radians(double(cone_deg_))),
               cos_falloff = std::cos(glm::radians(double(falloff_deg_)));
  // spot.h: Phi = 2 pi I (1 - (cos falloff + cos cone) / 2), the smoothstep integrated over the cone.
  if (!profile_) return 2.0 * M_PI * (1.0 - 0.5 * (cos_falloff + cos_cone));
  const auto smooth = [=](double c) {
    if (c >= cos_falloff) return 1.0;
    if (c <= cos_cone) return 0.0;
    const double t = (c - cos_cone) / (cos_falloff - cos_cone);
    return t * t * (3.0 - 2.0 * t);
  };
  return profile_->integral(smooth, {double(falloff_deg_), double(cone_deg_)});
}

Rgb SpotLight::power() const { return intensity_ * float(solid_angle_); }

Deferred<Light> SpotLight::parse(const JsonObject& l) {
  const Vec3 pos = get_point(l, "position");
  Vec3 dir;
  if (l.has("look_at") == l.has("direction")) l.fail("give exactly one of 'look_at' or 'direction'");
  if (l.has("look_at")) {
    dir = get_point(l, "look_at") - pos;
    if (!(glm::dot(dir, dir) > 0.0f)) l.fail("look_at", "look_at must differ from position");
  } else {
    dir = l.get_direction("direction");
  }
  const LightStrength strength = read_strength(l, "intensity");
  const float cone = l.get_float("cone_angle", 30.0f, Range{0.0, 180.0, true, true});
  const float falloff = l.get_float("falloff_angle", std::min(25.0f, cone), Range::closed(0.0, cone));
  if (!l.has("profile")) {
    Rgb intensity = strength.value;
    if (strength.is_power)
      intensity = power_to(l, strength.value, SpotLight(pos, dir, Rgb(1.0f), cone, falloff).solid_angle(),
                           "axial intensity (W/sr)");
    return std::make_unique<SpotLight>(pos, dir, intensity, cone, falloff);
  }
  const std::filesystem::path file = l.get_path("profile");
  return Deferred<Light>([=]() -> std::unique_ptr<Light> {
    const std::shared_ptr<const IesProfile> profile = IesProfile::load_for(l, file);
    Rgb intensity = strength.value;
    if (strength.is_power)
      intensity = power_to(l, strength.value, SpotLight(pos, dir, Rgb(1.0f), cone, falloff, profile).solid_angle(),
                           "peak intensity (W/sr)");
    return std::make_unique<SpotLight>(pos, dir, intensity, cone, falloff, profile);
  });
}

}  // namespace kozu
