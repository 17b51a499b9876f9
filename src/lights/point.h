// point: a point light of radiant intensity I (W/sr): isotropic (power 4 pi I), or shaped by an IES profile
// (lights/ies_profile.h): I(w) = I profile(w), the profile's largest value 1, power I x the profile's integral.
//
// Parameters
//   position   vec3  required
//   intensity  rgb   required (or power), >= 0   (W/sr; with a profile, the peak intensity)
//   power      rgb   instead of intensity, >= 0   (W; lights/light_power.h): I = power / (4 pi), or
//                                                 power / (the profile's integral over the sphere)
//   profile    path  -                             IES LM-63 file
//   direction  vec3  [0, -1, 0]                    the profile's nadir (theta = 0); C = 0 as luminaire_frame says
#pragma once

#include "core/registry.h"
#include "lights/ies_profile.h"
#include "lights/light.h"

#include <memory>

namespace kozu {

// Sample of an isotropic point emitter of intensity I at position: direction and distance to it,
// "radiance" I / r^2 (the delta light's irradiance per unit cosine), pdf 1.
LightSample sample_point_emitter(const Vec3& position, const Rgb& intensity, const LightSampleContext& ctx);

class PointLight final : public DeltaLight {
 public:
  PointLight(const Vec3& position, const Rgb& intensity) : position_(position), intensity_(intensity) {}
  // Shaped by profile, its nadir along the unit vector nadir.
  PointLight(const Vec3& position, const Rgb& intensity, std::shared_ptr<const IesProfile> profile, const Vec3& nadir);
  static Deferred<Light> parse(const JsonObject& desc);
  LightSample sample(const LightSampleContext& ctx, const Vec2& u) const override;
  Rgb power() const override { return intensity_ * solid_angle_; }
  LightBounds bounds() const override {
    return LightBounds{position_, position_, DirectionCone{Vec3(0, 0, 1), kPi, 0.5f * kPi}, average(intensity_)};
  }
  bool aim_point(Vec3* p) const override {
    *p = position_;
    return true;
  }

 private:
  Vec3 position_;
  Rgb intensity_;
  std::shared_ptr<const IesProfile> profile_;
  Frame frame_;
  float solid_angle_ = 4.0f * kPi;  // the integral of I(w) / I over the sphere
};

}  // namespace kozu
