#include "lights/spot.h"

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
  return t * t * (3.0f - 2.0f * t);
}

LightSample SpotLight::sample(const LightSampleContext& ctx, const Vec2&) const {
  LightSample ls = sample_point_emitter(position_, intensity_, ctx);
  ls.radiance *= falloff(glm::dot(-ls.wi, frame_.n));
  return ls;
}

Rgb SpotLight::power() const { return intensity_ * (kTwoPi * (1.0f - 0.5f * (cos_falloff_ + cos_cone_))); }

}  // namespace kozu
