#include "materials/cod_multiscatter_diffuse.h"

namespace kozu {

namespace {
float pow5(float x) {
  const float x2 = x * x;
  return x2 * x2 * x;
}
}  // namespace

CodMultiscatterDiffuseBsdf::CodMultiscatterDiffuseBsdf(const Rgb& albedo, float gloss)
    : albedo_(albedo),
      t_(std::clamp(2.2f * gloss - 0.5f, 0.0f, 1.0f)),       // eq. (66)
      bump_scale_((34.5f * gloss - 59.0f) * gloss + 24.5f),  // eq. (68)
      bump_rate_(std::max(73.2f * gloss - 21.2f, 8.9f)) {}   // eq. (68)

float CodMultiscatterDiffuseBsdf::shape(const Vec3& wo, const Vec3& wi) const {
  const float nl = abs_cos_theta(wi), nv = abs_cos_theta(wo);
  // With h = (l + v) / |l + v|: l·h = v·h = |l + v| / 2 and, on wo's side, n·h = (n·l + n·v) / |l + v|.
  // No normalised h is formed, so l = -v (both in the horizon) needs no special case.
  const float len = glm::length(wo + wi);
  const float lh = std::min(0.5f * len, 1.0f);
  const float nh = len > 0.0f ? std::min((nl + nv) / len, 1.0f) : 0.0f;
  const float f0 = lh + pow5(1.0f - lh);                                                 // eq. (64)
  const float f1 = (1.0f - 0.75f * pow5(1.0f - nl)) * (1.0f - 0.75f * pow5(1.0f - nv));  // eq. (65)
  const float fd = f0 + (f1 - f0) * t_;                                                  // eq. (67)
  const float fb = bump_scale_ * lh * std::exp2(-bump_rate_ * std::sqrt(nh));            // eq. (68)
  return std::max(fd + fb, 0.0f);  // clamped: fb < 0 for g in (0.71, 1), see the header
}

Rgb CodMultiscatterDiffuseBsdf::eval(const Vec3& wo, const Vec3& wi, TransportMode) const {
  if (!same_hemisphere(wo, wi)) return Rgb(0.0f);
  return albedo_ * (shape(wo, wi) * (abs_cos_theta(wi) * kInvPi));  // eq. (69), times |cos theta_i|
}

BsdfSample CodMultiscatterDiffuseBsdf::sample(const Vec3& wo, float, const Vec2& u, TransportMode) const {
  BsdfSample s = sample_cosine_lobe(wo, u);
  if (s.valid()) s.f = albedo_ * (shape(wo, s.wi) * s.pdf);  // pdf = |cos theta_i| / pi
  return s;
}

float CodMultiscatterDiffuseBsdf::pdf(const Vec3& wo, const Vec3& wi) const { return cosine_lobe_pdf(wo, wi); }

Rgb CodMultiscatterDiffuseBsdf::eval_pdf(const Vec3& wo, const Vec3& wi, float* pdf_out, TransportMode) const {
  const float p = cosine_lobe_pdf(wo, wi);
  *pdf_out = p;
  return p > 0.0f ? albedo_ * (shape(wo, wi) * p) : Rgb(0.0f);
}

}  // namespace kozu
