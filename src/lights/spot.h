// spot: a point light emitting into a cone, with a smooth falloff at its edge.
//
// Parameters
//   position       vec3   required
//   look_at        vec3   required (or `direction`)
//   intensity      rgb    required (or power), >= 0    intensity on the axis (W/sr; with a profile, the peak)
//   power          rgb    instead of intensity, >= 0 (W; lights/light_power.h)
//   profile        path   -    IES LM-63 file (lights/ies_profile.h): its nadir is the axis, C = 0 as
//                              luminaire_frame says; it multiplies the falloff
//   cone_angle     float  30   in (0, 180)   half-angle of the lit cone, degrees
//   falloff_angle  float  25   in [0, cone_angle]  half-angle where the falloff starts, degrees
//
// I(theta) = intensity * smoothstep(cos cone_angle, cos falloff_angle, cos theta) (as in pbrt-v4);
// power 2 pi I (1 - (cos falloff + cos cone) / 2). With a profile, I(w) = intensity profile(w) smoothstep(...), and
// power intensity x the integral of profile x smoothstep over the sphere (IesProfile::integral).
#pragma once

#include "core/frame.h"
#include "core/registry.h"
#include "lights/ies_profile.h"
#include "lights/light.h"

#include <memory>

namespace kozu {

class SpotLight final : public DeltaLight {
 public:
  SpotLight(const Vec3& position, const Vec3& direction, const Rgb& intensity, float cone_deg, float falloff_deg,
            std::shared_ptr<const IesProfile> profile = nullptr);
  static Deferred<Light> parse(const JsonObject& desc);
  LightSample sample(const LightSampleContext& ctx, const Vec2& u) const override;
  Rgb power() const override;
  // Lit within the falloff's start about the axis (θo), fading to nothing at the cone's edge (θe beyond it).
  LightBounds bounds() const override {
    const float falloff = glm::radians(falloff_deg_);
    return LightBounds{position_, position_, DirectionCone{frame_.n, falloff, glm::radians(cone_deg_) - falloff},
                       average(intensity_)};
  }
  bool aim_point(Vec3* p) const override {
    *p = position_;
    return true;
  }
  float falloff(float cos_theta) const;
  // The integral over the sphere of I(w) / intensity: power() / intensity (in double).
  double solid_angle() const;

 private:
  Vec3 position_;
  Frame frame_;
  Rgb intensity_;
  float cos_cone_, cos_falloff_;
  float cone_deg_, falloff_deg_;
  std::shared_ptr<const IesProfile> profile_;
  double solid_angle_;
};

}  // namespace kozu
