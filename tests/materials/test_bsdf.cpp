// BSDF models: chi-square of sample against pdf, sample/eval/pdf consistency, normalisation,
// reciprocity, and the exact laws of the smooth (delta) models.
#include "support/chi2.h"

#include "core/rng.h"
#include "materials/conductor.h"
#include "materials/dielectric.h"
#include "materials/diffuse.h"
#include "materials/fresnel.h"
#include "materials/metal_data.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace kozu::test {
namespace {

Vec3 direction_from_angles(float theta_deg, float phi_deg) {
  const float t = glm::radians(theta_deg), p = glm::radians(phi_deg);
  return Vec3(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
}

// The chi-square family in this file, for the Šidák correction.
constexpr int kChi2Tests = 5;

class DiffuseChi2 : public ::testing::TestWithParam<float> {};

TEST_P(DiffuseChi2, SampleMatchesPdf) {
  const DiffuseBsdf bsdf(Rgb(0.7f));
  const Vec3 wo = direction_from_angles(GetParam(), 30.0f);
  Chi2Options opt;
  opt.test_count = kChi2Tests;
  const Chi2Result r = chi2_test(
      [&](const Vec2& u) -> std::optional<Vec3> {
        const BsdfSample s = bsdf.sample(wo, 0.5f, u, TransportMode::Radiance);
        if (!s.valid()) return std::nullopt;
        return s.wi;
      },
      [&](const Vec3& wi) { return static_cast<double>(bsdf.pdf(wo, wi)); }, opt);
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_integral, 1.0, 1e-3);
}
// Includes wo below the shading horizon: the diffuse BSDF is two-sided.
INSTANTIATE_TEST_SUITE_P(Angles, DiffuseChi2, ::testing::Values(0.0f, 45.0f, 80.0f, 120.0f, 179.0f));

TEST(Diffuse, SampleAgreesWithEvalAndPdf) {
  const DiffuseBsdf bsdf(Rgb(0.2f, 0.5f, 0.9f));
  Pcg32 rng(5);
  for (int i = 0; i < 10000; ++i) {
    const Vec3 wo = direction_from_angles(180.0f * rng.next_float(), 360.0f * rng.next_float());
    const BsdfSample s =
        bsdf.sample(wo, rng.next_float(), Vec2(rng.next_float(), rng.next_float()), TransportMode::Radiance);
    if (!s.valid()) continue;
    const Rgb f = bsdf.eval(wo, s.wi, TransportMode::Radiance);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.f[c], f[c], 1e-6f * std::max(1.0f, f[c]));
    EXPECT_NEAR(s.pdf, bsdf.pdf(wo, s.wi), 1e-6f * std::max(1.0f, s.pdf));
    float p2;
    const Rgb f2 = bsdf.eval_pdf(wo, s.wi, &p2, TransportMode::Radiance);
    EXPECT_EQ(p2, bsdf.pdf(wo, s.wi));
    EXPECT_EQ(f2, f);
    // Albedo-weighted estimator: f / pdf is the albedo exactly for cosine sampling.
    EXPECT_NEAR(s.weight().g, 0.5f, 1e-5f);
  }
}

TEST(Diffuse, Reciprocity) {
  const DiffuseBsdf bsdf(Rgb(0.6f));
  Pcg32 rng(9);
  for (int i = 0; i < 1000; ++i) {
    const Vec3 a = direction_from_angles(89.0f * rng.next_float(), 360.0f * rng.next_float());
    const Vec3 b = direction_from_angles(89.0f * rng.next_float(), 360.0f * rng.next_float());
    // eval includes |cos theta_i|: divide it out to compare f itself.
    const float fab = bsdf.eval(a, b, TransportMode::Radiance).r / abs_cos_theta(b);
    const float fba = bsdf.eval(b, a, TransportMode::Radiance).r / abs_cos_theta(a);
    EXPECT_NEAR(fab, fba, 1e-5f);
  }
}

// Smooth dielectric: lobe frequencies follow the Fresnel reflectance, directions follow the laws of
// reflection and refraction exactly, and the throughput weights are 1 (reflection) and 1/eta^2
// (transmission, radiance transport).
struct DielectricCase {
  float ior;
  float theta_deg;  // > 90: wo inside the medium
};
class SmoothDielectricLaws : public ::testing::TestWithParam<DielectricCase> {};

TEST_P(SmoothDielectricLaws, FresnelSnellAndWeights) {
  const auto [ior, theta] = GetParam();
  const SmoothDielectricBsdf bsdf(ior);
  const Vec3 wo = direction_from_angles(theta, 40.0f);
  const float expected_r = fresnel_dielectric(cos_theta(wo), ior);
  Pcg32 rng(11);
  constexpr int kN = 200000;
  int reflected = 0;
  for (int i = 0; i < kN; ++i) {
    const BsdfSample s =
        bsdf.sample(wo, rng.next_float(), Vec2(rng.next_float(), rng.next_float()), TransportMode::Radiance);
    ASSERT_TRUE(s.valid());
    ASSERT_TRUE(s.delta());
    if (s.flags & kBsdfReflection) {
      ++reflected;
      EXPECT_NEAR(glm::length(s.wi - Vec3(-wo.x, -wo.y, wo.z)), 0.0f, 1e-6f);
      EXPECT_NEAR(s.weight().r, 1.0f, 1e-6f);
    } else {
      // Snell: n_o sin(theta_o) = n_i sin(theta_i), opposite side, opposite azimuth.
      const float eta_o = cos_theta(wo) > 0 ? 1.0f : ior, eta_i = cos_theta(wo) > 0 ? ior : 1.0f;
      EXPECT_NEAR(eta_o * sin_theta(wo), eta_i * sin_theta(s.wi), 1e-5f);
      EXPECT_LT(cos_theta(wo) * cos_theta(s.wi), 0.0f);
      EXPECT_NEAR(s.wi.x * wo.y - s.wi.y * wo.x, 0.0f, 1e-6f);  // same plane of incidence
      EXPECT_LT(s.wi.x * wo.x + s.wi.y * wo.y, 1e-6f);          // opposite azimuth
      EXPECT_NEAR(s.weight().r, sqr(eta_o / eta_i), 1e-5f);
      EXPECT_NEAR(s.eta, eta_i / eta_o, 1e-6f);
    }
  }
  // Binomial: 5 standard deviations.
  const double p = reflected / static_cast<double>(kN);
  const double sd = std::sqrt(std::max(expected_r * (1 - expected_r), 1e-12f) / kN);
  EXPECT_NEAR(p, expected_r, 5 * sd + 1e-12) << "ior " << ior << " theta " << theta;
}

INSTANTIATE_TEST_SUITE_P(Cases, SmoothDielectricLaws,
                         ::testing::Values(DielectricCase{1.5f, 0.0f}, DielectricCase{1.5f, 60.0f},
                                           DielectricCase{1.5f, 89.0f}, DielectricCase{1.5f, 150.0f},
                                           DielectricCase{1.5f, 135.0f},  // beyond the critical angle: TIR
                                           DielectricCase{1.33f, 170.0f}, DielectricCase{0.8f, 30.0f}));

TEST(SmoothDielectric, TotalInternalReflectionBeyondCriticalAngle) {
  // From inside glass (ior 1.5) the critical angle is asin(1/1.5) = 41.8 degrees.
  EXPECT_EQ(fresnel_dielectric(std::cos(glm::radians(42.5f)) * -1.0f, 1.5f), 1.0f);
  EXPECT_LT(fresnel_dielectric(std::cos(glm::radians(41.0f)) * -1.0f, 1.5f), 1.0f);
}

TEST(SmoothDielectric, ImportanceTransportOmitsEtaSquared) {
  const SmoothDielectricBsdf bsdf(1.5f);
  const Vec3 wo = direction_from_angles(30.0f, 0.0f);
  const BsdfSample s = bsdf.sample(wo, 0.99f, Vec2(0.5f), TransportMode::Importance);
  ASSERT_TRUE(s.flags & kBsdfTransmission);
  EXPECT_NEAR(s.weight().r, 1.0f, 1e-6f);
}

// Conductor Fresnel: closed forms at normal and grazing incidence, and the k = 0 limit equals the
// dielectric equations.
TEST(ConductorFresnel, ClosedFormLimits) {
  for (const MetalIor& m : kMetals) {
    for (int c = 0; c < 3; ++c) {
      const float n = m.eta[c], k = m.k[c];
      const float r0 = (sqr(n - 1) + k * k) / (sqr(n + 1) + k * k);
      EXPECT_NEAR(fresnel_conductor(1.0f, n, k), r0, 1e-5f) << m.name;
      EXPECT_NEAR(fresnel_conductor(0.0f, n, k), 1.0f, 1e-5f) << m.name;
    }
  }
  for (float eta : {1.2f, 1.5f, 2.4f})
    for (float c = 0.05f; c <= 1.0f; c += 0.05f)
      EXPECT_NEAR(fresnel_conductor(c, eta, 0.0f), fresnel_dielectric(c, eta), 2e-6f);
}

TEST(SmoothConductor, MirrorDirectionAndFresnelWeight) {
  const MetalIor* gold = find_metal("gold");
  ASSERT_NE(gold, nullptr);
  const ConductorFresnel gold_f{gold->eta, gold->k, false};
  const SmoothConductorBsdf bsdf(&gold_f);
  const Vec3 wo = direction_from_angles(50.0f, 10.0f);
  const BsdfSample s = bsdf.sample(wo, 0.3f, Vec2(0.2f, 0.7f), TransportMode::Radiance);
  EXPECT_TRUE(s.delta());
  EXPECT_NEAR(glm::length(s.wi - Vec3(-wo.x, -wo.y, wo.z)), 0.0f, 1e-6f);
  const Rgb f = fresnel_conductor(cos_theta(wo), gold->eta, gold->k);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.weight()[c], f[c], 1e-6f);
  const ConductorFresnel perfect_f;
  const SmoothConductorBsdf perfect(&perfect_f);
  EXPECT_EQ(perfect.sample(wo, 0.3f, Vec2(0.2f, 0.7f), TransportMode::Radiance).weight(), Rgb(1.0f));
}

}  // namespace
}  // namespace kozu::test
