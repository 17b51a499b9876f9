// The Henyey–Greenstein phase function (media/hg_phase.h): normalization, sampling against its pdf by
// chi-square, symmetry (an isotropic medium's phase function is reciprocal), and its mean cosine is g.
#include "media/hg_phase.h"

#include "support/chi2.h"

#include <gtest/gtest.h>

namespace kozu {
namespace {

constexpr float kG[] = {0.0f, 0.3f, 0.7f, -0.5f, 0.95f};

TEST(HgPhase, NormalizedAndMeanCosineIsG) {
  const Vec3 wo = glm::normalize(Vec3(0.3f, -0.2f, 0.9f));
  Pcg32 rng(1);
  for (float g : kG) {
    const HgPhase p(g);
    const double total = test::integrate_pdf_over_sphere([&](const Vec3& w) { return double(p.eval(wo, w, rng)); }, 128);
    EXPECT_NEAR(total, 1.0, g > 0.9f ? 2e-3 : 1e-4) << "g " << g;
    // Mean cosine of the scattering angle between the propagation direction −wo and wi (as ∫ f (1 + cos) − 1:
    // the integrator takes non-negative integrands).
    const double mean_cos =
        test::integrate_pdf_over_sphere([&](const Vec3& w) { return double(p.eval(wo, w, rng)) * (1.0 + glm::dot(-wo, w)); }, 128) - 1.0;
    EXPECT_NEAR(mean_cos, g, g > 0.9f ? 5e-3 : 1e-4) << "g " << g;
    // Reciprocal: f(wo, wi) = f(wi, wo).
    const Vec3 wi = glm::normalize(Vec3(-0.5f, 0.1f, 0.2f));
    EXPECT_FLOAT_EQ(p.eval(wo, wi, rng), p.eval(wi, wo, rng));
  }
}

TEST(HgPhase, SamplingMatchesPdfChi2) {
  const Vec3 wo = glm::normalize(Vec3(0.3f, -0.2f, 0.9f));
  for (float g : kG) {
    const HgPhase p(g);
    Pcg32 rng(2);
    test::Chi2Options opt;
    opt.test_count = 5;
    opt.check_lost_mass = g < 0.9f;
    const test::Chi2Result r = test::chi2_test(
        [&](const Vec2& u) -> std::optional<Vec3> {
          const PhaseSample s = p.sample(wo, u, rng);
          if (!s.valid()) return std::nullopt;
          EXPECT_NEAR(s.pdf, p.pdf(wo, s.wi), 1e-3f * s.pdf);
          EXPECT_EQ(s.weight(), 1.0f);
          return s.wi;
        },
        [&](const Vec3& w) { return double(p.pdf(wo, w)); }, opt);
    EXPECT_TRUE(r.passed) << "g " << g << ": " << r.message;
  }
}

}  // namespace
}  // namespace kozu
