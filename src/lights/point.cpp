#include "lights/point.h"

#include "core/input_bounds.h"
#include "lights/light_power.h"

namespace kozu {

LightSample sample_point_emitter(const Vec3& position, const Rgb& intensity, const LightSampleContext& ctx) {
  LightSample ls;
  const Vec3 d = position - ctx.p;
  const float dist2 = glm::dot(d, d);
  if (!(dist2 > 0.0f)) return ls;
  ls.wi = d / std::sqrt(dist2);
  ls.p = position;
  ls.pdf = 1.0f;
  ls.radiance = intensity / dist2;  // inverse-square law: E = I cos / r^2, the cosine is the receiver's
  return ls;
}

PointLight::PointLight(const Vec3& position, const Rgb& intensity, std::shared_ptr<const IesProfile> profile,
                       const Vec3& nadir)
    : position_(position),
      intensity_(intensity),
      profile_(std::move(profile)),
      frame_(luminaire_frame(nadir)),
      solid_angle_(float(profile_->integral())) {}

LightSample PointLight::sample(const LightSampleContext& ctx, const Vec2&) const {
  LightSample ls = sample_point_emitter(position_, intensity_, ctx);
  if (profile_ && ls.valid()) ls.radiance *= profile_->eval(frame_.to_local(-ls.wi));
  return ls;
}

Deferred<Light> PointLight::parse(const JsonObject& l) {
  const Vec3 position = get_point(l, "position");
  const LightStrength strength = read_strength(l, "intensity");
  if (!l.has("profile")) {
    if (l.has("direction")) {
      l.get_direction("direction");
      l.warn("direction", "'direction' orients a 'profile' and has no effect without one");
    }
    // point.h: Phi = 4 pi I
    const Rgb intensity =
        strength.is_power ? power_to(l, strength.value, 4.0 * M_PI, "intensity (W/sr)") : strength.value;
    return std::make_unique<PointLight>(position, intensity);
  }
  const std::filesystem::path file = l.get_path("profile");
  const Vec3 nadir = glm::normalize(l.get_direction("direction", Vec3(0.0f, -1.0f, 0.0f)));
  return Deferred<Light>([=]() -> std::unique_ptr<Light> {
    const std::shared_ptr<const IesProfile> profile = IesProfile::load_for(l, file);
    // Phi = I x the profile's integral
    const Rgb intensity =
        strength.is_power ? power_to(l, strength.value, profile->integral(), "peak intensity (W/sr)") : strength.value;
    return std::make_unique<PointLight>(position, intensity, profile, nadir);
  });
}

}  // namespace kozu
