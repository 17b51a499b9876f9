// spot: a point light emitting into a cone, with a smooth falloff at its edge.
//
// Parameters
//   position       vec3   required
//   look_at        vec3   required (or `direction`)
//   intensity      rgb    required, >= 0    intensity on the axis (W/sr)
//   cone_angle     float  30   in (0, 180)   half-angle of the lit cone, degrees
//   falloff_angle  float  25   in [0, cone_angle]  half-angle where the falloff starts, degrees
//
// I(theta) = intensity * smoothstep(cos cone_angle, cos falloff_angle, cos theta) (as in pbrt-v4);
// power 2 pi I (1 - (cos falloff + cos cone) / 2).
#pragma once

#include "core/frame.h"
#include "core/registry.h"
#include "lights/light.h"

namespace kozu {

class SpotLight final : public DeltaLight {
 public:
  SpotLight(const Vec3& position, const Vec3& direction, const Rgb& intensity, float cone_deg, float falloff_deg);
  static Deferred<Light> parse(const JsonObject& desc);
  LightSample sample(const LightSampleContext& ctx, const Vec2& u) const override;
  Rgb power() const override;
  float falloff(float cos_theta) const;

 private:
  Vec3 position_;
  Frame frame_;
  Rgb intensity_;
  float cos_cone_, cos_falloff_;
};

}  // namespace kozu
