#include "materials/diffuse.h"

#include "core/warp.h"
#include "io/json_reader.h"

namespace kozu {

Rgb DiffuseBsdf::eval(const Vec3& wo, const Vec3& wi, TransportMode) const {
  if (!same_hemisphere(wo, wi)) return Rgb(0.0f);
  return albedo_ * (kInvPi * abs_cos_theta(wi));
}

BsdfSample DiffuseBsdf::sample(const Vec3& wo, float, const Vec2& u, TransportMode) const {
  BsdfSample s;
  if (wo.z == 0.0f) return s;
  Vec3 wi = warp::square_to_cosine_hemisphere(u);
  if (wi.z <= 0.0f) return s;     // grazing sample on the disk's rim
  if (wo.z < 0.0f) wi.z = -wi.z;  // two-sided: reflect on wo's side
  s.wi = wi;
  s.pdf = abs_cos_theta(wi) * kInvPi;
  s.f = albedo_ * s.pdf;
  s.flags = kBsdfReflection | kBsdfDiffuse;
  return s;
}

float DiffuseBsdf::pdf(const Vec3& wo, const Vec3& wi) const {
  return same_hemisphere(wo, wi) ? abs_cos_theta(wi) * kInvPi : 0.0f;
}

Rgb DiffuseBsdf::eval_pdf(const Vec3& wo, const Vec3& wi, float* pdf_out, TransportMode) const {
  const float p = same_hemisphere(wo, wi) ? abs_cos_theta(wi) * kInvPi : 0.0f;
  *pdf_out = p;
  return albedo_ * p;
}

std::unique_ptr<Material> DiffuseMaterial::create(const JsonObject& desc) {
  return std::make_unique<DiffuseMaterial>(desc.get_rgb("albedo", Rgb(0.5f), Range::unit()));
}

const Bsdf* DiffuseMaterial::bsdf(const SurfaceInteraction&, Arena& arena) const {
  return arena.make<DiffuseBsdf>(albedo_);
}

}  // namespace kozu
