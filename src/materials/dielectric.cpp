#include "materials/dielectric.h"

#include "io/json_reader.h"
#include "materials/fresnel.h"

namespace kozu {

BsdfSample SmoothDielectricBsdf::sample(const Vec3& wo, float u_lobe, const Vec2&, TransportMode mode) const {
  BsdfSample s;
  const float cos_o = cos_theta(wo);
  if (cos_o == 0.0f) return s;
  const float r = fresnel_dielectric(cos_o, eta_);
  const float t = 1.0f - r;
  if (u_lobe < r) {
    s.wi = Vec3(-wo.x, -wo.y, wo.z);
    s.f = Rgb(r);
    s.pdf = r;
    s.flags = kBsdfReflection | kBsdfSpecular;
    return s;
  }
  // Relative IOR from wo's side to the other side.
  const bool outside = cos_o > 0.0f;
  const float eta = outside ? eta_ : 1.0f / eta_;
  Vec3 wi;
  if (!refract(wo, Vec3(0.0f, 0.0f, outside ? 1.0f : -1.0f), eta, &wi)) return s;  // unreachable: TIR has r = 1
  float ft = t;
  if (mode == TransportMode::Radiance) ft /= eta * eta;
  s.wi = wi;
  s.f = Rgb(ft);
  s.pdf = t;
  s.flags = kBsdfTransmission | kBsdfSpecular;
  s.eta = eta;
  return s;
}

std::unique_ptr<Material> DielectricMaterial::create(const JsonObject& desc) {
  return std::make_unique<DielectricMaterial>(desc.get_float("ior", 1.5f, Range::positive()));
}

const Bsdf* DielectricMaterial::bsdf(const SurfaceInteraction&, Arena& arena) const {
  return arena.make<SmoothDielectricBsdf>(ior_);
}

}  // namespace kozu
