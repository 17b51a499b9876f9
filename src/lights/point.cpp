#include "lights/point.h"

namespace kozu {

LightSample PointLight::sample(const LightSampleContext& ctx, const Vec2&) const {
  LightSample ls;
  const Vec3 d = position_ - ctx.p;
  const float dist2 = glm::dot(d, d);
  if (!(dist2 > 0.0f)) return ls;
  ls.wi = d / std::sqrt(dist2);
  ls.p = position_;
  ls.pdf = 1.0f;
  ls.radiance = intensity_ / dist2;  // delta light: "radiance" is intensity / r^2 (irradiance per unit cos)
  return ls;
}

}  // namespace kozu
