#include "integrators/lobe_light_sampler.h"

#include <algorithm>
#include <array>

namespace kozu {

LobeLightSampler::LobeLightSampler(const Frame& frame, const Vec3& p, std::span<const LtcLobe> lobes,
                                   const DiffuseAreaLight& light)
    : frame_(frame), light_(&light) {
  const std::span<const EmitterTriangle> triangles = light.flat_triangles();
  if (triangles.empty() || triangles.size() > size_t(LtcPolygonSampler::kMaxTriangles) || !light.faces(p))
    return;
  // The narrowest lobe that carries light.
  int g = -1;
  for (int k = 0; k < int(lobes.size()); ++k)
    if (lobes[k].ltc.det_inv() >= kMinConcentration && luminance(lobes[k].weight) > 0.0f &&
        (g < 0 || lobes[k].ltc.det_inv() > lobes[g].ltc.det_inv()))
      g = k;
  if (g < 0) return;
  // Before any sampler is built: the light's solid angle Ω' in the lobe's cosine configuration (the light's own
  // solid angle times the Jacobian |M⁻¹| / ‖M⁻¹ω‖³ of eq. 1 at each triangle's centre), and from it the lobe's share
  // q, w_g ∫_P D_g against the other lobes' weights times ∫_P D_o, each integral estimated as the solid angle times
  // the cosine at the centre (they set only the variance; the closed forms, eq. 11, cost more than the sampler).
  const Ltc& lobe = lobes[g].ltc;
  float omega_lobe = 0.0f, taken = 0.0f, cosine = 0.0f;
  std::array<std::array<Vec3, 3>, LtcPolygonSampler::kMaxTriangles> tris;
  for (size_t t = 0; t < triangles.size(); ++t) {
    const EmitterTriangle& e = triangles[t];
    tris[t] = {frame.to_local(e.p0 - p), frame.to_local(e.p0 + e.e1 - p), frame.to_local(e.p0 + e.e2 - p)};
    const Vec3 c = (tris[t][0] + tris[t][1] + tris[t][2]) * (1.0f / 3.0f);
    const float r = glm::length(c);
    if (!(r > 0.0f)) continue;
    const Vec3 w = c / r;
    const float omega = std::min(e.area * std::abs(glm::dot(frame.to_local(e.n), w)) / (r * r), kTwoPi);
    const Vec3 v = lobe.m_inv() * w;
    const float len = glm::length(v);
    if (!(len > 0.0f)) continue;
    const float o = std::min(omega * lobe.det_inv() / (len * len * len), kTwoPi);
    omega_lobe += o;
    taken += o * std::max(0.0f, v.z / len);
    cosine += omega * std::max(0.0f, w.z);
  }
  if (!(omega_lobe >= LtcPolygonSampler::kMinSolidAngle) || !(taken > 0.0f)) return;
  float rest = 0.0f;
  for (int k = 0; k < int(lobes.size()); ++k)
    if (k != g) rest += luminance(lobes[k].weight);
  taken *= luminance(lobes[g].weight);
  const float q = std::min(taken / (taken + rest * cosine), kMaxFraction);
  if (!(q >= kMinFraction)) return;
  lobe_ = lobe;
  sampler_.emplace(lobe_, std::span<const std::array<Vec3, 3>>(tris.data(), triangles.size()));
  if (sampler_->valid()) q_ = q;
}

LightSample LobeLightSampler::sample(const LightSampleContext& ctx, const Vec2& u) const {
  LightSample ls;
  if (u.x < q_) {
    // The lobe's direction, then the point where it meets the light.
    const Vec3 w = glm::normalize(frame_.to_world(sampler_->sample(Vec2(u.x / q_, u.y))));
    if (!light_->along(ctx, w, &ls)) return LightSample{};
  } else {
    ls = light_->sample(ctx, Vec2(std::min((u.x - q_) / (1.0f - q_), 0x1.fffffep-1f), u.y));
    if (!ls.valid()) return ls;
  }
  ls.pdf = pdf(ls.wi, ls.pdf);
  return ls;
}

float LobeLightSampler::pdf(const Vec3& wi, float light_pdf) const {
  return q_ * sampler_->pdf(frame_.to_local(wi)) + (1.0f - q_) * light_pdf;
}

}  // namespace kozu
