#include "lights/spot.h"

#include "core/input_bounds.h"
#include "lights/point.h"

namespace kozu {

SpotLight::SpotLight(const Vec3& position, const Vec3& direction, const Rgb& intensity, float cone_deg,
                     float falloff_deg)
    : position_(position),
      frame_(glm::normalize(direction)),
      intensity_(intensity),
      cos_cone_(std::cos(glm::radians(cone_deg))),
      cos_falloff_(std::cos(glm::radians(falloff_deg))) {}

float SpotLight::falloff(float cos_theta) const {
  if (cos_theta >= cos_falloff_) return 1.0f;
  if (cos_theta <= cos_cone_) return 0.0f;
  const float t = (cos_theta - cos_cone_) / (cos_falloff_ - cos_cone_);
  return t * t * (3.0f - 2.0f * t);  // spot.h: I(theta) = I smoothstep(cos cone, cos falloff, cos theta)
}

LightSample SpotLight::sample(const LightSampleContext& ctx, const Vec2&) const {
  LightSample ls = sample_point_emitter(position_, intensity_, ctx);
  ls.radiance *= falloff(glm::dot(-ls.wi, frame_.n));
  return ls;
}

// spot.h: Phi = 2 pi I (1 - (cos falloff + cos cone) / 2), the smoothstep integrated over the cone.
Rgb SpotLight::power() const { return intensity_ * (kTwoPi * (1.0f - 0.5f * (cos_falloff_ + cos_cone_))); }

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
  const Rgb intensity = l.get_rgb("intensity");
  const float cone = l.get_float("cone_angle", 30.0f, Range{0.0, 180.0, true, true});
  const float falloff = l.get_float("falloff_angle", std::min(25.0f, cone), Range::closed(0.0, cone));
  return std::make_unique<SpotLight>(pos, dir, intensity, cone, falloff);
}

}  // namespace kozu
