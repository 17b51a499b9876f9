// The `diffuse` material's non-Lambertian models, cod-multiscatter (Chan 2018 eqs. 64–69) and shirley
// (Chan 2018 eqs. 61–62): chi-square of sample against pdf, sample/eval/pdf consistency, normalisation,
// reciprocity, non-negativity and finiteness up to the horizon, the Shirley closed-form albedo, and the
// CoD model's qualitative claims (flattening when rough, rounding when smooth) as measured albedos.
#include "support/chi2.h"

#include "core/rng.h"
#include "materials/cod_multiscatter_diffuse.h"
#include "materials/diffuse.h"
#include "materials/shirley_diffuse.h"
#include "core/gauss_legendre.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <array>
#include <vector>

namespace kozu::test {
namespace {

Vec3 direction_from_angles(float theta_deg, float phi_deg) {
  const float t = glm::radians(theta_deg), p = glm::radians(phi_deg);
  return Vec3(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
}
// Unit direction with cos theta = mu (may be negative) at azimuth phi (radians).
Vec3 direction_from_cos(float mu, float phi) {
  const float s = safe_sqrt(1.0f - mu * mu);
  return Vec3(s * std::cos(phi), s * std::sin(phi), mu);
}

// One model with its parameter (gloss for cod-multiscatter, F0 for shirley), built through
// DiffuseMaterial so the dispatch on `model` is exercised too.
struct ModelCase {
  DiffuseModel model;
  float param;
  float theta_deg;  // incident (wo) angle for the chi-square test; > 90: below the shading horizon
  // Every model samples the same cosine lobe, so with one seed all cases would draw the same directions
  // (mirrored below the horizon) and give the same statistic; a seed per case makes them independent.
  uint64_t seed;
};

std::string case_name(const ModelCase& c) {
  return fmt::format("{}{}_theta{}", c.model == DiffuseModel::CodMultiscatter ? "Cod_gloss" : "Shirley_f0",
                     static_cast<int>(std::lround(c.param * 100)), static_cast<int>(c.theta_deg));
}

DiffuseParams params_of(DiffuseModel model, float param, const Rgb& albedo) {
  DiffuseParams p;
  p.model = model;
  p.albedo = albedo;
  if (model == DiffuseModel::CodMultiscatter)
    p.gloss = param;
  else
    p.f0 = param;
  return p;
}

// A model's BSDF, with the arena it lives in.
class Built {
 public:
  Built(DiffuseModel model, float param, const Rgb& albedo = Rgb(1.0f))
      : material_(params_of(model, param, albedo)), bsdf_(material_.bsdf(SurfaceInteraction{}, arena_)) {}
  const Bsdf& operator*() const { return *bsdf_; }
  const Bsdf* operator->() const { return bsdf_; }

 private:
  Arena arena_;
  DiffuseMaterial material_;
  const Bsdf* bsdf_;
};

// Gloss values of the CoD cases cover t = 0 (g <= 0.227), the blend, the negative bump (0.71 < g < 1)
// and g = 1 (no bump); angles cover normal, oblique, grazing and below-horizon (two-sided) incidence.
const std::vector<ModelCase> kChi2Cases = {
    {DiffuseModel::CodMultiscatter, 0.0f, 0.0f, 1},   {DiffuseModel::CodMultiscatter, 0.5f, 45.0f, 2},
    {DiffuseModel::CodMultiscatter, 0.85f, 85.0f, 3}, {DiffuseModel::CodMultiscatter, 1.0f, 120.0f, 4},
    {DiffuseModel::Shirley, 0.04f, 30.0f, 5},         {DiffuseModel::Shirley, 0.5f, 89.0f, 6},
    {DiffuseModel::Shirley, 0.04f, 170.0f, 7},
};

class DiffuseModelChi2 : public ::testing::TestWithParam<ModelCase> {};

TEST_P(DiffuseModelChi2, SampleMatchesPdf) {
  const ModelCase c = GetParam();
  const Built bsdf(c.model, c.param);
  const Vec3 wo = direction_from_angles(c.theta_deg, 30.0f);
  Chi2Options opt;
  opt.test_count = static_cast<int>(kChi2Cases.size());  // the family: every chi-square test in this file
  opt.seed = c.seed;
  const Chi2Result r = chi2_test(
      [&](const Vec2& u) -> std::optional<Vec3> {
        const BsdfSample s = bsdf->sample(wo, 0.5f, u, TransportMode::Radiance);
        if (!s.valid()) return std::nullopt;
        return s.wi;
      },
      [&](const Vec3& wi) { return static_cast<double>(bsdf->pdf(wo, wi)); }, opt);
  EXPECT_TRUE(r.passed) << r.message;
  RecordProperty("p_value", fmt::format("{:.4g}", r.p_value));
  // pdf normalisation: the harness's 8x8-point Gauss–Legendre integral over 40x80 cells; the pdf is
  // smooth except for its cut at the horizon, which lies on a cell edge, so 1e-3 is generous.
  EXPECT_NEAR(r.pdf_integral, 1.0, 1e-3);
  EXPECT_NEAR(integrate_pdf_over_sphere([&](const Vec3& wi) { return static_cast<double>(bsdf->pdf(wo, wi)); }, 32),
              1.0, 1e-4);
}

INSTANTIATE_TEST_SUITE_P(Models, DiffuseModelChi2, ::testing::ValuesIn(kChi2Cases),
                         [](const auto& p) { return case_name(p.param); });

// Every model and parameter value tested below, beyond the chi-square cases.
struct ModelParam {
  DiffuseModel model;
  float param;
};
std::vector<ModelParam> all_model_params() {
  std::vector<ModelParam> v;
  for (int i = 0; i <= 20; ++i) v.push_back({DiffuseModel::CodMultiscatter, i / 20.0f});
  v.push_back({DiffuseModel::CodMultiscatter, 0.7101f});  // a root of the bump's coefficient
  for (float f0 : {0.0f, 0.04f, 0.5f, 1.0f}) v.push_back({DiffuseModel::Shirley, f0});
  return v;
}

TEST(DiffuseModels, SampleAgreesWithEvalAndPdf) {
  for (const ModelParam& mp : all_model_params()) {
    const Built bsdf(mp.model, mp.param, Rgb(0.2f, 0.5f, 0.9f));
    Pcg32 rng(5);
    for (int i = 0; i < 2000; ++i) {
      const Vec3 wo = direction_from_angles(180.0f * rng.next_float(), 360.0f * rng.next_float());
      const BsdfSample s =
          bsdf->sample(wo, rng.next_float(), Vec2(rng.next_float(), rng.next_float()), TransportMode::Radiance);
      if (!s.valid()) continue;
      ASSERT_TRUE(same_hemisphere(wo, s.wi));
      ASSERT_EQ(s.flags, kBsdfReflection | kBsdfDiffuse);
      const Rgb f = bsdf->eval(wo, s.wi, TransportMode::Radiance);
      for (int c = 0; c < 3; ++c) ASSERT_NEAR(s.f[c], f[c], 1e-6f * std::max(1.0f, f[c])) << "param " << mp.param;
      ASSERT_NEAR(s.pdf, bsdf->pdf(wo, s.wi), 1e-6f * std::max(1.0f, s.pdf));
      ASSERT_NEAR(s.pdf, abs_cos_theta(s.wi) * kInvPi, 1e-6f);
      float p2;
      const Rgb f2 = bsdf->eval_pdf(wo, s.wi, &p2, TransportMode::Radiance);
      ASSERT_EQ(p2, bsdf->pdf(wo, s.wi));
      ASSERT_EQ(f2, f) << "param " << mp.param;
    }
  }
}

TEST(DiffuseModels, Reciprocity) {
  for (const ModelParam& mp : all_model_params()) {
    const Built bsdf(mp.model, mp.param);
    Pcg32 rng(9);
    for (int i = 0; i < 2000; ++i) {
      // Both hemispheres (two-sided), down to cos theta = 1e-4 (0.006 degree above the horizon).
      const float side = i % 2 ? 1.0f : -1.0f;
      const Vec3 a = direction_from_cos(side * (1e-4f + (1 - 1e-4f) * rng.next_float()), kTwoPi * rng.next_float());
      const Vec3 b = direction_from_cos(side * (1e-4f + (1 - 1e-4f) * rng.next_float()), kTwoPi * rng.next_float());
      // eval includes |cos theta_i|: divide it out to compare f itself.
      const float fab = bsdf->eval(a, b, TransportMode::Radiance).r / abs_cos_theta(b);
      const float fba = bsdf->eval(b, a, TransportMode::Radiance).r / abs_cos_theta(a);
      ASSERT_NEAR(fab, fba, 1e-5f * std::max(1.0f, fab)) << "param " << mp.param;
    }
  }
}

// eval, pdf and sample stay finite and non-negative on a grid that reaches the horizon: cos theta down to
// 1e-7 (and exactly 0, where the BSDF is 0), azimuth differences including l = -v and l = v. The CoD
// bump is negative for 0.71 < g < 1 and outweighs fd where both directions graze; the model clamps it.
TEST(DiffuseModels, NonNegativeAndFiniteUpToTheHorizon) {
  const float mus[] = {0.0f, 1e-7f, 1e-5f, 1e-3f, 0.01f, 0.05f, 0.2f, 0.5f, 0.9f, 1.0f};
  const float phis[] = {0.0f, 0.3f, kPiOver2, 2.5f, kPi};
  for (const ModelParam& mp : all_model_params()) {
    const Built bsdf(mp.model, mp.param);
    for (float side : {1.0f, -1.0f})
      for (float mo : mus)
        for (float mi : mus)
          for (float phi : phis) {
            const Vec3 wo = direction_from_cos(side * mo, 0.0f), wi = direction_from_cos(side * mi, phi);
            float p;
            const Rgb f = bsdf->eval_pdf(wo, wi, &p, TransportMode::Radiance);
            ASSERT_TRUE(std::isfinite(f.r) && f.r >= 0.0f) << mp.param << " " << mo << " " << mi << " " << phi;
            ASSERT_TRUE(std::isfinite(p) && p >= 0.0f);
          }
    Pcg32 rng(3);
    for (float mo : mus)
      for (int i = 0; i < 200; ++i) {
        const BsdfSample s = bsdf->sample(direction_from_cos(mo, 1.0f), rng.next_float(),
                                          Vec2(rng.next_float(), rng.next_float()), TransportMode::Radiance);
        if (!s.valid()) continue;
        ASSERT_TRUE(is_finite(s.wi) && std::isfinite(s.pdf) && std::isfinite(s.f.r) && s.f.r >= 0.0f);
        ASSERT_TRUE(std::isfinite(s.weight().r));
      }
  }
}

// The clamp is reached: g = 0.85 with l = v both 0.006 degrees above the horizon gives, unclamped,
// fd + fb = f1 + (34.5 g² − 59 g + 24.5) 2^(−41.02 sqrt(1e-4)) = 0.0628 − 0.724 * 0.753 < 0.
TEST(CodMultiscatterDiffuse, NegativeGrazingBumpIsClampedToZero) {
  const CodMultiscatterDiffuseBsdf bsdf(Rgb(1.0f), 0.85f);
  const Vec3 w = direction_from_cos(1e-4f, 0.0f);
  EXPECT_EQ(bsdf.shape(w, w), 0.0f);
  // Above the bump's reach it is positive again (n·h = 0.1: fb = -0.724 * 2^(-13) is negligible).
  const Vec3 w2 = direction_from_cos(0.1f, 0.0f);
  EXPECT_GT(bsdf.shape(w2, w2), 0.1f);
}

// --- Directional albedo by deterministic quadrature -------------------------------------------------

// 8-point Gauss–Legendre rule on [-1, 1].
constexpr std::array<double, 4> kGlX = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
constexpr std::array<double, 4> kGlW = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};

// Directional albedo for wo with cos theta_o = mu_o at phi = 0: the integral of f(wo, wi) (the value times
// |cos theta_i|, as eval returns it) over wi's hemisphere, composite Gauss–Legendre in (cos theta_i, phi_i) with
// 32 panels of 8 points in each; wo lies in the xz-plane so the integrand is even in phi and phi runs over
// [0, pi], doubled. Its accuracy for cod-multiscatter is measured by AlbedoMatchesSeedQuadrature.
template <class F>
double directional_albedo(float mu_o, const F& f) {
  constexpr int kPanels = 32;
  const Vec3 wo = direction_from_cos(mu_o, 0.0f);
  double sum = 0;
  for (int a = 0; a < kPanels; ++a)
    for (int qa = 0; qa < 8; ++qa) {
      const double xa = qa < 4 ? -kGlX[qa] : kGlX[qa - 4], wa = kGlW[qa % 4];
      const double mu = (a + 0.5 * (xa + 1)) / kPanels;
      const double w_mu = 0.5 * wa / kPanels;
      for (int b = 0; b < kPanels; ++b)
        for (int qb = 0; qb < 8; ++qb) {
          const double xb = qb < 4 ? -kGlX[qb] : kGlX[qb - 4], wb = kGlW[qb % 4];
          const double phi = kPi * (b + 0.5 * (xb + 1)) / kPanels;
          const double w_phi = kPi * 0.5 * wb / kPanels;
          const Vec3 wi = direction_from_cos(static_cast<float>(mu), static_cast<float>(phi));
          sum += 2 * w_mu * w_phi * f(wo, wi);
        }
    }
  return sum;
}

// The same for a BSDF (its red channel).
double directional_albedo(const Bsdf& bsdf, float mu_o) {
  return directional_albedo(mu_o, [&](const Vec3& wo, const Vec3& wi) {
    return static_cast<double>(bsdf.eval(wo, wi, TransportMode::Radiance).r);
  });
}

// Shirley: A(mu_o) = rho (1 − F0)(1 − (1 − mu_o)^5) (derivation in shirley_diffuse.h). The integrand is a
// degree-6 polynomial in mu_i, integrated exactly by the rule, so 1e-4 only has to absorb float rounding.
TEST(ShirleyDiffuse, AlbedoMatchesClosedForm) {
  const float rho = 0.8f;
  for (float f0 : {0.0f, 0.04f, 0.5f, 1.0f}) {
    const ShirleyDiffuseBsdf bsdf(Rgb(rho), f0);
    for (float mu_o : {1.0f, 0.7f, 0.3f, 0.05f, 0.001f}) {
      const double expected = rho * (1.0 - f0) * (1.0 - std::pow(1.0 - mu_o, 5.0));
      EXPECT_NEAR(directional_albedo(bsdf, mu_o), expected, 1e-4) << "f0 " << f0 << " mu_o " << mu_o;
      EXPECT_NEAR(bsdf.directional_albedo(direction_from_cos(mu_o, 0.3f)).r, expected, 1e-6);
      EXPECT_NEAR(bsdf.directional_albedo(direction_from_cos(-mu_o, 0.3f)).r, expected, 1e-6);  // two-sided
    }
  }
}

// Albedos with rho = 1, so Lambert's is 1 at every angle.
double cod_albedo(float gloss, float mu_o) {
  return directional_albedo(CodMultiscatterDiffuseBsdf(Rgb(1.0f), gloss), mu_o);
}

// At g = 1, t = 1 and the bump's coefficient is 0, so fr = f1 / pi and the albedo has a closed form:
// (1 − 0.75 (1 − mu_o)^5) * 2 integral_0^1 (1 − 0.75 (1 − mu)^5) mu dmu = (1 − 0.75 (1 − mu_o)^5) (1 − 0.75 / 21),
// i.e. 27/28 (1 − 0.75 (1 − mu_o)^5). Checks the quadrature and eqs. (65)–(69) together.
TEST(CodMultiscatterDiffuse, SmoothAlbedoMatchesClosedForm) {
  for (float mu_o : {1.0f, 0.7f, 0.3f, 0.1f, 0.01f}) {
    const double expected = 27.0 / 28.0 * (1.0 - 0.75 * std::pow(1.0 - mu_o, 5.0));
    EXPECT_NEAR(cod_albedo(1.0f, mu_o), expected, 1e-4) << "mu_o " << mu_o;
  }
}

constexpr double kPiD = 3.14159265358979323846;

// Chan 2018 §5.8, eqs. (64)–(69), in double precision and written from the paper, for rho = 1: pi fr = fd + fb
// (clamped at 0 only when `clamp`: kozu's documented deviation), for l and v in the upper hemisphere.
double seed_pi_fr(double g, const Vec3d& l, const Vec3d& v, bool clamp) {
  const Vec3d h = glm::normalize(l + v);
  const double nl = l.z, nv = v.z, nh = h.z, lh = glm::dot(l, h);
  const double f0 = lh + std::pow(1 - lh, 5);                                             // (64)
  const double f1 = (1 - 0.75 * std::pow(1 - nl, 5)) * (1 - 0.75 * std::pow(1 - nv, 5));  // (65)
  const double t = std::clamp(2.2 * g - 0.5, 0.0, 1.0);                                   // (66)
  const double fd = f0 + (f1 - f0) * t;                                                   // (67)
  const double fb =
      (34.5 * g * g - 59 * g + 24.5) * lh * std::exp2(-std::max(73.2 * g - 21.2, 8.9) * std::sqrt(nh));  // (68)
  return clamp ? std::max(fd + fb, 0.0) : fd + fb;  // (69), times pi / rho
}

// A(mu_o) = (1/pi) integral of (fd + fb) cos theta_l over l's hemisphere, by composite Gauss–Legendre in
// (cos theta_l, phi_l) with `order` points per panel, panels graded towards cos theta_l = 0 (where sqrt(n·h)
// varies fastest for grazing views) at widths 2^-k, and no panel wider than 1/16 in cos theta or pi/16 in phi;
// phi over [0, pi], doubled, as above.
double seed_albedo(double g, double mu_o, bool clamp, int order) {
  const GaussLegendre rule(order);  // on [-1, 1]
  const std::vector<double>& x = rule.x;
  const std::vector<double>& w = rule.w;
  std::vector<double> mu_edges{0.0};
  for (double e = 0x1p-20; e < 1.0 / 16; e *= 2) mu_edges.push_back(e);
  for (int k = 1; k <= 16; ++k) mu_edges.push_back(k / 16.0);
  const Vec3d v(std::sqrt(1 - mu_o * mu_o), 0.0, mu_o);
  double sum = 0;
  for (size_t a = 1; a < mu_edges.size(); ++a) {
    const double mu_c = 0.5 * (mu_edges[a] + mu_edges[a - 1]), mu_h = 0.5 * (mu_edges[a] - mu_edges[a - 1]);
    for (int p = 0; p < order; ++p) {
      const double mu = mu_c + mu_h * x[static_cast<size_t>(p)], sin_t = std::sqrt(1 - mu * mu);
      for (int b = 0; b < 16; ++b)
        for (int q = 0; q < order; ++q) {
          const double phi = kPiD / 16 * (b + 0.5 * (x[static_cast<size_t>(q)] + 1));
          const Vec3d l(sin_t * std::cos(phi), sin_t * std::sin(phi), mu);
          sum += mu_h * w[static_cast<size_t>(p)] * (kPiD / 32 * w[static_cast<size_t>(q)]) *
                 seed_pi_fr(g, l, v, clamp) * mu;
        }
    }
  }
  return 2 * sum / kPiD;
}

// cod_albedo against the paper's equations integrated in double. The tolerance is the sum of what may separate
// them, each measured here rather than chosen:
//  - the quadrature error of directional_albedo's rule: that rule applied to the paper's equations (in double,
//    at the same float directions) against the fine reference;
//  - kozu's clamp of fd + fb at 0 (docs/materials.md: < 3e-6), as the clamped reference's distance from the
//    paper's, which must itself stay below the documented 3e-6;
//  - float evaluation: a few dozen roundings of 2^-24 relative per evaluation, 32 * 2^-24 of the albedo;
// and the reference's own error, the difference between 12- and 16-point panels (required to be negligible).
TEST(CodMultiscatterDiffuse, AlbedoMatchesSeedQuadrature) {
  for (const float g : {0.0f, 0.25f, 0.5f, 0.75f, 0.85f, 1.0f}) {
    for (const float mu_o : {1.0f, 0.7f, 0.5f, 0.3f, 0.1f, 0.05f, 0.01f}) {
      const double reference = seed_albedo(g, mu_o, false, 16);
      const double reference_error = std::abs(reference - seed_albedo(g, mu_o, false, 12));
      ASSERT_LT(reference_error, 1e-7) << "g " << g << " mu_o " << mu_o;
      const double clamp_effect = std::abs(seed_albedo(g, mu_o, true, 16) - reference);
      EXPECT_LT(clamp_effect, 3e-6) << "g " << g << " mu_o " << mu_o;
      const double rule = directional_albedo(mu_o, [&](const Vec3& wo, const Vec3& wi) {
        return seed_pi_fr(g, Vec3d(wi), Vec3d(wo), false) * std::abs(double(wi.z)) / kPiD;
      });
      const double rule_error = std::abs(rule - reference);
      const double tol = rule_error + clamp_effect + 32 * 0x1p-24 * reference + reference_error;
      EXPECT_NEAR(cod_albedo(g, mu_o), reference, tol) << "g " << g << " mu_o " << mu_o;
    }
  }
}

// The paper's §5.4 claims, as facts about the albedo relative to Lambert (whose albedo is 1 for every
// view). The margins below are orders of magnitude above the quadrature error (< 1e-5).
//  - Rough (g = 0) flattens: grazing views reflect more than Lambert while normal view reflects slightly
//    less (A(0.1) = 1.045, A(1) = 0.973), so grazing / normal = 1.074 > 1 = Lambert's ratio.
//  - Smooth (g = 1) rounds: at grazing view much of the light is lost to the specular coat
//    (A(0.1) = 0.537, A(0.01) = 0.276) while normal view keeps 27/28 = 0.964.
TEST(CodMultiscatterDiffuse, RoughFlattensAndSmoothRoundsRelativeToLambert) {
  const double rough_normal = cod_albedo(0.0f, 1.0f), rough_grazing = cod_albedo(0.0f, 0.1f);
  EXPECT_LT(rough_normal, 1.0);
  EXPECT_GT(rough_grazing, 1.0 + 0.03);
  EXPECT_GT(rough_grazing / rough_normal, 1.05);

  const double smooth_normal = cod_albedo(1.0f, 1.0f), smooth_grazing = cod_albedo(1.0f, 0.1f);
  EXPECT_GT(smooth_normal, 0.95);
  EXPECT_LT(smooth_grazing, 0.6);
  EXPECT_LT(cod_albedo(1.0f, 0.01f), 0.3);

  // Between the two, grazing albedo falls as gloss rises (0.25: 0.872, 0.5: 0.618).
  EXPECT_GT(rough_grazing, cod_albedo(0.25f, 0.1f) + 0.1);
  EXPECT_GT(cod_albedo(0.25f, 0.1f), cod_albedo(0.5f, 0.1f) + 0.1);
  EXPECT_GT(cod_albedo(0.5f, 0.1f), smooth_grazing + 0.05);
}

// Retro-reflection of rough surfaces (§5.1): at g = 0, with light and view 80 degrees from the normal,
// light returning towards itself (l = v: l·h = 1, n·h = cos 80°, fd = 1, fb = 24.5 * 2^(-8.9 sqrt 0.174)
// = 1.87) is 5.06 times brighter than light leaving in the mirror direction (l·h = cos 80°, n·h = 1,
// fd = 0.559, fb = 0.0089); Lambert's ratio is 1. At g = 1 there is no bump and f depends on n·l and
// n·v only: ratio 1.
TEST(CodMultiscatterDiffuse, RoughSurfacesRetroReflectAtGrazingAngles) {
  const Vec3 v = direction_from_angles(80.0f, 0.0f), mirror = direction_from_angles(80.0f, 180.0f);
  const CodMultiscatterDiffuseBsdf rough(Rgb(1.0f), 0.0f), smooth(Rgb(1.0f), 1.0f);
  EXPECT_GT(rough.shape(v, v), 3.0f * rough.shape(v, mirror));
  EXPECT_NEAR(smooth.shape(v, v), smooth.shape(v, mirror), 1e-6f);
}

// The material picks the BSDF named by `model`.
TEST(DiffuseMaterial, DispatchesOnModel) {
  Arena arena;
  const SurfaceInteraction si{};
  const auto* lambert = DiffuseMaterial(Rgb(0.5f)).bsdf(si, arena);
  EXPECT_NE(dynamic_cast<const DiffuseBsdf*>(lambert), nullptr);
  const auto* cod = DiffuseMaterial(params_of(DiffuseModel::CodMultiscatter, 0.3f, Rgb(0.5f))).bsdf(si, arena);
  EXPECT_NE(dynamic_cast<const CodMultiscatterDiffuseBsdf*>(cod), nullptr);
  const auto* shirley = DiffuseMaterial(params_of(DiffuseModel::Shirley, 0.04f, Rgb(0.5f))).bsdf(si, arena);
  EXPECT_NE(dynamic_cast<const ShirleyDiffuseBsdf*>(shirley), nullptr);
}

}  // namespace
}  // namespace kozu::test
