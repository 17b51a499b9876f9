// point: an isotropic point light of radiant intensity I (W/sr); power 4 pi I.
//
// Parameters
//   position   vec3  required
//   intensity  rgb   required, >= 0   (W/sr)
#pragma once

#include "core/registry.h"
#include "lights/light.h"

namespace kozu {

// Sample of an isotropic point emitter of intensity I at position: direction and distance to it,
// "radiance" I / r^2 (the delta light's irradiance per unit cosine), pdf 1.
LightSample sample_point_emitter(const Vec3& position, const Rgb& intensity, const LightSampleContext& ctx);

class PointLight final : public DeltaLight {
 public:
  PointLight(const Vec3& position, const Rgb& intensity) : position_(position), intensity_(intensity) {}
  static Deferred<Light> parse(const JsonObject& desc);
  LightSample sample(const LightSampleContext& ctx, const Vec2& u) const override;
  Rgb power() const override { return 4.0f * kPi * intensity_; }

 private:
  Vec3 position_;
  Rgb intensity_;
};

}  // namespace kozu
