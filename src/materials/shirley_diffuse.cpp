#include "materials/shirley_diffuse.h"

namespace kozu {

namespace {
float pow5(float x) {
  const float x2 = x * x;
  return x2 * x2 * x;
}
// 1 − (1 − mu)^5: the coat's transmittance factor for one crossing, eq. (62).
float crossing(float mu) { return 1.0f - pow5(1.0f - mu); }
}  // namespace

ShirleyDiffuseBsdf::ShirleyDiffuseBsdf(const Rgb& albedo, float f0)
    : albedo_(albedo), one_minus_f0_(1.0f - f0), scale_(albedo * (21.0f / (20.0f * kPi) * (1.0f - f0))) {}  // eq. (61)

Rgb ShirleyDiffuseBsdf::eval(const Vec3& wo, const Vec3& wi, TransportMode) const {
  if (!same_hemisphere(wo, wi)) return Rgb(0.0f);
  const float nl = abs_cos_theta(wi), nv = abs_cos_theta(wo);
  return scale_ * (crossing(nl) * crossing(nv) * nl);  // eq. (62), times |cos theta_i|
}

BsdfSample ShirleyDiffuseBsdf::sample(const Vec3& wo, float, const Vec2& u, TransportMode mode) const {
  BsdfSample s = sample_cosine_lobe(wo, u);
  if (s.valid()) s.f = eval(wo, s.wi, mode);
  return s;
}

float ShirleyDiffuseBsdf::pdf(const Vec3& wo, const Vec3& wi) const { return cosine_lobe_pdf(wo, wi); }

Rgb ShirleyDiffuseBsdf::eval_pdf(const Vec3& wo, const Vec3& wi, float* pdf_out, TransportMode mode) const {
  *pdf_out = cosine_lobe_pdf(wo, wi);
  return eval(wo, wi, mode);
}

Rgb ShirleyDiffuseBsdf::directional_albedo(const Vec3& wo) const {
  return albedo_ * (one_minus_f0_ * crossing(abs_cos_theta(wo)));
}

}  // namespace kozu
