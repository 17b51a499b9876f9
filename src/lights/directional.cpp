#include "lights/directional.h"

#include "core/input_bounds.h"
#include "lights/light_power.h"

namespace kozu {

namespace {
// Unit vector towards the light, normalised in double so that any finite nonzero direction works.
Vec3 towards_light(const Vec3& direction) { return Vec3(-glm::normalize(Vec3d(direction))); }
}  // namespace

DirectionalLight::DirectionalLight(const Vec3& direction, const Rgb& irradiance, float angular_diameter_degrees)
    : frame_(towards_light(direction)), irradiance_(irradiance), delta_(!(angular_diameter_degrees > 0.0f)) {
  if (delta_) return;
  const double theta_max = 0.5 * glm::radians(static_cast<double>(angular_diameter_degrees));
  const double half_sin = std::sin(0.5 * theta_max);
  const double one_minus_cos = 2.0 * half_sin * half_sin;  // 1 - cos theta_max without cancellation
  const double sin2 = std::sin(theta_max) * std::sin(theta_max);
  one_minus_cos_max_ = static_cast<float>(one_minus_cos);
  radiance_ = Rgb(Vec3d(irradiance) / (M_PI * sin2));             // eq. (1)
  pdf_ = static_cast<float>(1.0 / (2.0 * M_PI * one_minus_cos));  // eq. (2)
}

void DirectionalLight::preprocess(const Vec3&, float radius) { scene_radius_ = std::max(radius, 1e-3f); }

Rgb DirectionalLight::power() const { return irradiance_ * (kPi * scene_radius_ * scene_radius_); }  // eq. (4)

// 1 - cos theta = |w - axis|^2 / 2 for unit w: exact to float precision however small the angle.
bool DirectionalLight::in_cone(const Vec3& w) const {
  const Vec3 d = w - frame_.n;
  return 0.5f * glm::dot(d, d) <= one_minus_cos_max_;
}

LightSample DirectionalLight::sample(const LightSampleContext&, const Vec2& u) const {
  LightSample ls;
  ls.infinite = true;
  if (delta_) {
    ls.wi = frame_.n;
    ls.pdf = 1.0f;
    ls.radiance = irradiance_;  // a delta light's "radiance" is its irradiance per unit cosine (light.h)
    return ls;
  }
  const float omc = u.x * one_minus_cos_max_;  // eq. (3): 1 - cos theta
  const float sin_t = std::sqrt(std::max(0.0f, omc * (2.0f - omc)));
  const float phi = kTwoPi * u.y;
  ls.wi = glm::normalize(frame_.to_world(Vec3(sin_t * std::cos(phi), sin_t * std::sin(phi), 1.0f - omc)));
  ls.pdf = pdf_;
  ls.radiance = radiance_;
  return ls;
}

Rgb DirectionalLight::eval(const LightHit& hit) const {
  if (delta_ || !in_cone(hit.wi)) return Rgb(0.0f);
  return radiance_;
}

float DirectionalLight::pdf(const LightSampleContext&, const LightHit& hit) const {
  if (delta_ || !in_cone(hit.wi)) return 0.0f;
  return pdf_;
}

Deferred<Light> DirectionalLight::parse(const JsonObject& l) {
  refuse_power(l, "irradiance",
               "a distant light's power depends on the scene's size (docs/lights.md \"Light power in watts\")");
  const Vec3 direction = l.get_direction("direction");
  const Rgb irradiance = l.get_rgb("irradiance");
  const float diameter = l.get_float("angular_diameter", 0.53f, Range::closed(0.0, 180.0));
  if (diameter > 0.0f) {
    // Eqs. (1) and (2) grow as 1 / diameter^2: keep density and radiance within float range on a path.
    const double theta_max = 0.5 * glm::radians(static_cast<double>(diameter));
    const double sin2 = std::sin(theta_max) * std::sin(theta_max);
    const double pdf = 1.0 / (2.0 * M_PI * 2.0 * std::pow(std::sin(0.5 * theta_max), 2.0));
    if (pdf > kMaxRadiance)
      l.fail("angular_diameter", fmt::format("{:g} degrees is too small to sample (density {:.3g}, beyond kozu's range "
                                             "of at most {:g}); use 0 for a delta directional light",
                                             diameter, pdf, kMaxRadiance));
    const double radiance = max_component(irradiance) / (M_PI * sin2);
    if (radiance > kMaxRadiance)
      l.fail("irradiance", fmt::format("over an angular diameter of {:g} degrees this is a radiance of {:.3g}, beyond "
                                       "kozu's range (at most {:g})",
                                       diameter, radiance, kMaxRadiance));
  }
  return std::make_unique<DirectionalLight>(direction, irradiance, diameter);
}

}  // namespace kozu
