// directional: light from a distant disk of given angular diameter (the sun), or from a single direction.
//
// Source: the radiometry of a uniform disk source and uniform cone sampling as in Pharr, Jakob, Humphreys,
// "Physically Based Rendering", 4th ed. (2023): "Integrals over Area" (the irradiance from a disk-shaped
// source, E = pi L sin^2 theta_max) and "Sampling a Cone" (Appendix A). No seed file covers it.
// Equations, with theta_max = angular_diameter / 2:
//   (1) L = E / (pi sin^2 theta_max)             uniform radiance over the cone; E is the irradiance on a
//                                                 surface facing the light (integral of L cos over the cone)
//   (2) pdf(w) = 1 / (2 pi (1 - cos theta_max))   uniform over the cone's solid angle, 0 outside
//   (3) 1 - cos theta = u1 (1 - cos theta_max), phi = 2 pi u2   the inverse CDF of (2)
//   (4) Phi = E pi R^2                            power through the scene's bounding disk (light selection)
//
// Parameters
//   direction         vec3   required, nonzero   the direction the light travels (from the light towards the
//                                                 scene): [0, -1, 0] is a sun at the zenith (+y up)
//   irradiance        rgb    required, >= 0       W/m^2 on a surface facing the light
//   angular_diameter  float  0.53  in [0, 180]    degrees; 0.53 is the mean angular diameter of the sun
//
// angular_diameter 0 is a delta directional light: every surface facing it receives E, no ray can meet it
// (is_delta, eval and pdf 0), and it casts hard shadows. Any positive diameter is an infinite light met by
// escaping rays (is_infinite), combined with BSDF sampling by MIS like the environment.
//
// Deviation from the book: 1 - cos theta is computed as |w - axis|^2 / 2 (and 1 - cos theta_max as
// 2 sin^2(theta_max / 2) in double), because for the sun 1 - cos theta_max is 1.07e-5, where cos theta
// rounded to a float keeps only two or three significant digits of it.
#pragma once

#include "core/frame.h"
#include "core/registry.h"
#include "lights/light.h"

namespace kozu {

class DirectionalLight final : public Light {
 public:
  // direction: where the light travels (need not be unit); angular_diameter in degrees, in [0, 180].
  DirectionalLight(const Vec3& direction, const Rgb& irradiance, float angular_diameter_degrees);
  static Deferred<Light> parse(const JsonObject& desc);

  LightSample sample(const LightSampleContext& ctx, const Vec2& u) const override;
  // L inside the cone around the direction towards the light, 0 outside (and 0 for the delta light).
  Rgb eval(const LightHit& hit) const override;
  float pdf(const LightSampleContext& ctx, const LightHit& hit) const override;
  Rgb power() const override;
  // Infinite (with or without a diameter): its irradiance E.
  LightBounds bounds() const override {
    LightBounds b;
    b.infinite = true;
    b.phi = average(irradiance_);
    return b;
  }
  void preprocess(const Vec3& center, float radius) override;
  bool is_delta() const override { return delta_; }
  bool is_infinite() const override { return !delta_; }

  Vec3 to_light() const { return frame_.n; }  // unit direction towards the light (-direction)
  Rgb radiance() const { return radiance_; }  // eq. (1); 0 for the delta light
  float one_minus_cos_max() const { return one_minus_cos_max_; }

 private:
  bool in_cone(const Vec3& w) const;

  Frame frame_;  // n points towards the light
  Rgb irradiance_;
  Rgb radiance_{0.0f};
  float one_minus_cos_max_ = 0;
  float pdf_ = 0;  // eq. (2)
  bool delta_;
  float scene_radius_ = 1;
};

}  // namespace kozu
