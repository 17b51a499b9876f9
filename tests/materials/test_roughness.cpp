// The Call of Duty gloss parameterizations (Chan 2018 eqs. 1-2) against the paper's formulas evaluated in double,
// their anchor points, and the inverse of eq. 2.
#include "materials/roughness.h"

#include <gtest/gtest.h>

#include <cmath>

namespace kozu {
namespace {

// Chan 2018 eq. (1), Advanced Warfare: α = sqrt(2 / (2 + 2^(16 g))); eq. (2), WWII: α = sqrt(2 / (1 + 2^(18 g))).
double alpha_aw(double g) { return std::sqrt(2.0 / (2.0 + std::pow(2.0, 16.0 * g))); }
double alpha_wwii(double g) { return std::sqrt(2.0 / (1.0 + std::pow(2.0, 18.0 * g))); }

TEST(Gloss, ForwardMapsFollowEquations1And2) {
  for (int i = 0; i <= 100; ++i) {
    const double g = i / 100.0;
    EXPECT_NEAR(gloss_to_alpha(float(g), GlossModel::WWII), alpha_wwii(g), 2e-7 + 2e-6 * alpha_wwii(g)) << g;
    EXPECT_NEAR(gloss_to_alpha(float(g), GlossModel::AdvancedWarfare), alpha_aw(g), 2e-7 + 2e-6 * alpha_aw(g)) << g;
  }
  // The anchors Chan 2018 and docs/materials.md state: WWII reaches α = 1 at g = 0 (the whole GGX range) and
  // gloss 1 is α = sqrt(2 / (1 + 2^18)) = 0.00276 (not the Advanced Warfare value sqrt(2 / (2 + 2^16)) = 0.00552).
  EXPECT_FLOAT_EQ(gloss_to_alpha(0.0f, GlossModel::WWII), 1.0f);
  EXPECT_NEAR(gloss_to_alpha(1.0f, GlossModel::WWII), 0.0027621, 1e-7);
  EXPECT_NEAR(gloss_to_alpha(0.0f, GlossModel::AdvancedWarfare), std::sqrt(2.0 / 3.0), 1e-7);
  EXPECT_NEAR(gloss_to_alpha(1.0f, GlossModel::AdvancedWarfare), 0.0055242, 1e-7);
}

TEST(Gloss, InverseOfEquation2RoundTrips) {
  for (int i = 0; i <= 100; ++i) {
    const float g = i / 100.0f;
    EXPECT_NEAR(alpha_to_gloss(gloss_to_alpha(g, GlossModel::WWII)), g, 2e-5f) << g;
  }
}

}  // namespace
}  // namespace kozu
