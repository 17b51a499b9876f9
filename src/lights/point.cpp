#include "lights/point.h"

#include "core/input_bounds.h"

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

LightSample PointLight::sample(const LightSampleContext& ctx, const Vec2&) const {
  return sample_point_emitter(position_, intensity_, ctx);
}

Deferred<Light> PointLight::parse(const JsonObject& l) {
  return std::make_unique<PointLight>(get_point(l, "position"), l.get_rgb("intensity"));
}

}  // namespace kozu
