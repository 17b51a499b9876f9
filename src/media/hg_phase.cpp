#include "media/hg_phase.h"

#include "core/frame.h"

namespace kozu {

namespace {
// Density per solid angle for c = wo · wi (forward scattering, wi = −wo, is c = −1).
inline float hg(float c, float g) {
  const float denom = 1.0f + g * g + 2.0f * g * c;
  return (1.0f - g * g) / (4.0f * kPi * denom * std::sqrt(std::max(denom, 1e-12f)));
}
}  // namespace

float HgPhase::pdf(const Vec3& wo, const Vec3& wi) const { return hg(glm::dot(wo, wi), g_); }

PhaseSample HgPhase::sample(const Vec3& wo, const Vec2& u, Pcg32&) const {
  // cos θ between the propagation direction −wo and wi.
  float cos_t;
  if (std::abs(g_) < 1e-3f) {
    cos_t = 1.0f - 2.0f * u.x;
  } else {
    const float s = (1.0f - g_ * g_) / (1.0f + g_ - 2.0f * g_ * u.x);
    cos_t = (1.0f + g_ * g_ - s * s) / (2.0f * g_);
  }
  cos_t = std::clamp(cos_t, -1.0f, 1.0f);
  const float sin_t = std::sqrt(std::max(0.0f, 1.0f - cos_t * cos_t));
  const float phi = kTwoPi * u.y;
  const Frame f(-wo);
  PhaseSample s;
  s.wi = glm::normalize(f.to_world(Vec3(sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t)));
  s.pdf = pdf(wo, s.wi);
  s.f = s.pdf;  // f_p sampled exactly
  return s;
}

}  // namespace kozu
