// The microsurface random walk (Heitz et al. 2016, materials/microsurface_walk.h): visible-normal sampling
// from below the horizon (which the walk relies on), white furnace, closed-form single scattering,
// sample/eval consistency by a two-sample chi-square, reciprocity, agreement of the bidirectional and
// forward estimators, and the single/multiple-scattering energy table.
//
// Statistics. Every eval is a random estimate, so the tests compare means with their standard errors:
// z-tests at 4.5 σ (two-sided p ≈ 7e-6 each) and chi-square tests at a family-wise 1% with the Šidák
// correction. All seeds are fixed.
#include "support/chi2.h"

#include "core/rng.h"
#include "core/warp.h"
#include "materials/fresnel.h"
#include "materials/metal_data.h"
#include "materials/microsurface_walk.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <vector>

namespace kozu::test {
namespace {

using warp::square_to_cosine_hemisphere;
using warp::square_to_uniform_hemisphere;
using warp::square_to_uniform_sphere;

constexpr double kZ = 4.5;  // z-test threshold

// The chi-square family of this file, for the Šidák correction: 8 visible-normal tests and 11 two-sample
// sample/eval tests.
constexpr int kChi2Family = 19;

Vec3 direction(float theta_deg, float phi_deg) {
  const float t = glm::radians(theta_deg), p = glm::radians(phi_deg);
  return Vec3(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
}

const char* name(MicrofacetType t) { return t == MicrofacetType::GGX ? "GGX" : "Beckmann"; }

// Running mean and standard error.
struct Mean {
  double sum = 0, sum2 = 0;
  int64_t n = 0;
  void add(double x) {
    sum += x;
    sum2 += x * x;
    ++n;
  }
  double mean() const { return n ? sum / n : 0.0; }
  double se() const {
    if (n < 2) return 0.0;
    const double m = mean();
    return std::sqrt(std::max(sum2 / n - m * m, 0.0) / (n - 1));
  }
};

// ---------------------------------------------------------------------------------------------------
// Reference closed forms (written independently of microsurface_walk.cpp).

// Density of the single-scattering VNDF reflection of wo (wo.z > 0) at w: D_wo(h) / (4 wo·h). Defined on
// the whole sphere: reflection on a steep facet can go below the horizon.
double vndf_reflection_pdf(const MicrofacetDistribution& d, const Vec3& wo, const Vec3& w) {
  const Vec3 h = glm::normalize(wo + w);
  const float oh = glm::dot(wo, h);
  return oh > 0.0f ? d.D_visible(wo, h) / (4.0 * oh) : 0.0;
}

// Half vector of a refraction from a (a.z > 0, IOR 1) into w (w.z < 0, relative IOR eta), m.z > 0, with
// Walter et al. 2007's Jacobian |w·m| eta² / (a·m + eta w·m)²; 0 if the pair is not a refraction.
double refraction_jacobian(const Vec3& a, const Vec3& w, float eta, Vec3* m_out) {
  Vec3 m = -(a + eta * w);
  const float len = glm::length(m);
  if (len <= 0.0f) return 0.0;
  m /= len;
  if (m.z < 0.0f) m = -m;
  const double am = glm::dot(a, m), wm = glm::dot(w, m);
  if (!(am > 0.0) || !(wm < 0.0)) return 0.0;
  *m_out = m;
  return std::abs(wm) * eta * eta / sqr(am + eta * wm);
}

// Density of the single-scattering VNDF refraction of a (a.z > 0, eta = IOR beyond / IOR on a's side), on
// the whole sphere (refraction through a steep facet can come out above the horizon).
double vndf_refraction_pdf(const MicrofacetDistribution& d, const Vec3& a, const Vec3& w, float eta) {
  Vec3 m;
  const double jacobian = refraction_jacobian(a, w, eta, &m);
  return jacobian > 0.0 ? d.D_visible(a, m) * jacobian : 0.0;
}

// Single-scattering conductor BRDF with F = 1, times cos θi: D(h) G2(wo, wi) / (4 cos θo).
double single_conductor(const MicrofacetDistribution& d, const Vec3& wo, const Vec3& wi) {
  if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0;
  const Vec3 h = glm::normalize(wo + wi);
  return d.D(h) * d.G2(wo, wi) / (4.0 * wo.z);
}

// Beta function B(x, y).
double beta(double x, double y) { return std::exp(std::lgamma(x) + std::lgamma(y) - std::lgamma(x + y)); }

// Single-scattering rough dielectric, f(wo, wi) |cos θi| in Importance mode (the walk density p(wi | wo)),
// eta = n_inside / n_outside. Reflection: F D G2 / (4 |cos θo|). Transmission: Walter et al. 2007,
// (1 − F) D G |wo·m| |wi·m| η² / (|cos θo| (wo·m + η wi·m)²), with η the IOR on wi's side over wo's and
// G the height-correlated transmission masking of Heitz 2014 for uniform heights, B(1 + Λo, 1 + Λi).
double single_dielectric_importance(const MicrofacetDistribution& d, const Vec3& wo, const Vec3& wi, float eta) {
  const float s = wo.z > 0.0f ? 1.0f : -1.0f;
  const Vec3 o(wo.x, wo.y, s * wo.z), i(wi.x, wi.y, s * wi.z);  // wo's side on top
  const float eta_l = s > 0.0f ? eta : 1.0f / eta;
  if (i.z > 0.0f) {
    const Vec3 h = glm::normalize(o + i);
    return fresnel_dielectric(glm::dot(o, h), eta_l) * d.D(h) * d.G2(o, i) / (4.0 * o.z);
  }
  Vec3 m;
  const double jacobian = refraction_jacobian(o, i, eta_l, &m);
  if (jacobian == 0.0) return 0.0;
  const double om = glm::dot(o, m);
  const double g = beta(1.0 + d.lambda(o), 1.0 + d.lambda(i));
  return (1.0 - fresnel_dielectric(static_cast<float>(om), eta_l)) * d.D(m) * om * g * jacobian / o.z;
}

// ---------------------------------------------------------------------------------------------------
// Monte Carlo integration of eval over directions, with known mixture densities.

// ∫ eval_conductor(wo, ω) dω over the hemisphere (channel c), accumulated into m: n directions from the
// mixture of VNDF reflection (probability p_vndf) and cosine-weighted directions.
void conductor_albedo(const MicrosurfaceWalk& walk, const Vec3& wo, const ConductorFresnel& F, int n, float p_vndf,
                      Pcg32& rng, Mean& m, int channel = 1) {
  const MicrofacetDistribution& d = walk.distribution();
  for (int k = 0; k < n; ++k) {
    const float sel = rng.next_float();
    const Vec2 u(rng.next_float(), rng.next_float());
    const Vec3 w = sel < p_vndf ? glm::normalize(reflect(wo, d.sample_visible(wo, u))) : square_to_cosine_hemisphere(u);
    if (w.z <= 0.0f) {
      m.add(0.0);
      continue;
    }
    const double pdf = p_vndf * vndf_reflection_pdf(d, wo, w) + (1.0 - p_vndf) * w.z * kInvPi;
    m.add(walk.eval_conductor(wo, w, F, rng)[channel] / pdf);
  }
}

// ∫ eval_dielectric(wo, ω) dω over the sphere, accumulated into mean: n directions from the mixture of
// single-scattering directions (a visible normal, then reflection or refraction chosen by its Fresnel
// reflectance; probability p_lobe) and uniform ones, in wo's side frame.
void dielectric_albedo(const MicrosurfaceWalk& walk, const Vec3& wo, float eta, TransportMode mode, int n, float p_lobe,
                       Pcg32& rng, Mean& mean) {
  const MicrofacetDistribution& d = walk.distribution();
  const float s = wo.z > 0.0f ? 1.0f : -1.0f;
  const float eta_l = s > 0.0f ? eta : 1.0f / eta;
  const Vec3 a(wo.x, wo.y, s * wo.z);
  auto lobe_pdf = [&](const Vec3& w) {
    double pdf = 0.0;
    const Vec3 h = glm::normalize(a + w);
    if (glm::dot(a, h) > 0.0f) pdf += fresnel_dielectric(glm::dot(a, h), eta_l) * vndf_reflection_pdf(d, a, w);
    Vec3 m;
    if (refraction_jacobian(a, w, eta_l, &m) > 0.0)
      pdf += (1.0 - fresnel_dielectric(glm::dot(a, m), eta_l)) * vndf_refraction_pdf(d, a, w, eta_l);
    return pdf;
  };
  for (int k = 0; k < n; ++k) {
    const float sel = rng.next_float();
    const Vec2 u(rng.next_float(), rng.next_float());
    Vec3 w;
    if (sel < p_lobe) {
      const Vec3 m = d.sample_visible(a, u);
      Vec3 t;
      if (rng.next_float() < fresnel_dielectric(glm::dot(a, m), eta_l) || !refract(a, m, eta_l, &t))
        w = glm::normalize(reflect(a, m));
      else
        w = glm::normalize(t);
    } else {
      w = square_to_uniform_sphere(u);
    }
    const double pdf = p_lobe * lobe_pdf(w) + (1.0 - p_lobe) * kInv4Pi;
    const Vec3 wg(w.x, w.y, s * w.z);
    mean.add(walk.eval_dielectric(wo, wg, eta, mode, rng) / pdf);
  }
}

// Adds batches of Monte Carlo samples until the 1% furnace tolerance is kZ standard errors or more (at
// least 2 batches, at most kMaxBatches): the test then fails only on a real deviation.
template <typename AddBatch>
Mean integrate_to_furnace_precision(AddBatch add_batch) {
  constexpr int kBatch = 25'000, kMaxBatches = 32;
  Mean m;
  for (int b = 0; b < kMaxBatches; ++b) {
    add_batch(kBatch, m);
    if (b >= 1 && kZ * m.se() < 0.01) break;
  }
  return m;
}

// ---------------------------------------------------------------------------------------------------
// Visible normals seen from below the horizon: the walk samples D_ω for rays travelling upwards, i.e.
// MicrofacetDistribution::sample_visible(ω) with ω.z < 0, whose density is ⟨ω, m⟩⁺ D(m) / (|ω.z| Λ(ω)).

struct VisibleCase {
  MicrofacetType type;
  float ax, ay;
  float theta, phi;  // theta > 90: from below
};
class VisibleNormalsFromBelow : public ::testing::TestWithParam<VisibleCase> {};

TEST_P(VisibleNormalsFromBelow, SampleMatchesDensity) {
  const VisibleCase c = GetParam();
  const MicrofacetDistribution d(c.type, c.ax, c.ay);
  const Vec3 w = direction(c.theta, c.phi);
  const double area = std::abs(w.z) * d.lambda(w);  // projected area of the facets facing w
  ASSERT_GT(area, 0.0);
  Chi2Options opt;
  opt.test_count = kChi2Family;
  opt.sample_count = 300'000;
  opt.theta_bins = 20;
  opt.phi_bins = 40;
  opt.cos_theta_min = 0.0;
  const Chi2Result r = chi2_test([&](const Vec2& u) -> std::optional<Vec3> { return d.sample_visible(w, u); },
                                 [&](const Vec3& m) { return std::max(0.0f, glm::dot(w, m)) * d.D(m) / area; }, opt);
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_integral, 1.0, 2e-3);  // the projected area A(ω) = |cos θ| Λ(ω) normalises it
}
INSTANTIATE_TEST_SUITE_P(Cases, VisibleNormalsFromBelow,
                         ::testing::Values(VisibleCase{MicrofacetType::GGX, 0.5f, 0.5f, 100.0f, 30.0f},
                                           VisibleCase{MicrofacetType::GGX, 1.0f, 1.0f, 135.0f, 0.0f},
                                           VisibleCase{MicrofacetType::GGX, 0.3f, 0.9f, 110.0f, 60.0f},
                                           VisibleCase{MicrofacetType::GGX, 0.8f, 0.8f, 95.0f, 200.0f},
                                           VisibleCase{MicrofacetType::Beckmann, 0.5f, 0.5f, 100.0f, 30.0f},
                                           VisibleCase{MicrofacetType::Beckmann, 1.0f, 1.0f, 135.0f, 0.0f},
                                           VisibleCase{MicrofacetType::Beckmann, 0.3f, 0.9f, 110.0f, 60.0f},
                                           VisibleCase{MicrofacetType::Beckmann, 0.8f, 0.8f, 95.0f, 200.0f}));

// ---------------------------------------------------------------------------------------------------
// White furnace.

struct ConductorCase {
  MicrofacetType type;
  float ax, ay;
  float theta;
};
std::string conductor_case_name(const ::testing::TestParamInfo<ConductorCase>& info) {
  const ConductorCase& c = info.param;
  return fmt::format("{}_a{}x{}_theta{}", name(c.type), static_cast<int>(std::lround(c.ax * 100)),
                     static_cast<int>(std::lround(c.ay * 100)), static_cast<int>(c.theta));
}

std::vector<ConductorCase> furnace_cases() {
  std::vector<ConductorCase> cases;
  for (MicrofacetType t : {MicrofacetType::GGX, MicrofacetType::Beckmann})
    for (float a : {0.1f, 0.3f, 0.6f, 1.0f})
      for (float theta : {0.0f, 45.0f, 75.0f}) cases.push_back({t, a, a, theta});
  // Anisotropic rows.
  cases.push_back({MicrofacetType::GGX, 0.1f, 0.8f, 60.0f});
  cases.push_back({MicrofacetType::Beckmann, 0.9f, 0.2f, 60.0f});
  return cases;
}

class ConductorFurnace : public ::testing::TestWithParam<ConductorCase> {};

// With F = 1 no energy is lost: every walk exits with weight exactly 1, and eval integrates to 1.
TEST_P(ConductorFurnace, EnergyIsConserved) {
  const ConductorCase c = GetParam();
  const MicrosurfaceWalk walk(MicrofacetDistribution(c.type, c.ax, c.ay));
  const ConductorFresnel perfect;
  const Vec3 wo = direction(c.theta, 20.0f);
  Pcg32 rng(17 + static_cast<uint64_t>(c.theta) * 7 + static_cast<uint64_t>(c.ax * 1000));

  constexpr int kWalks = 20000;
  int64_t orders = 0;
  for (int k = 0; k < kWalks; ++k) {
    Vec3 wi;
    Rgb weight;
    int order = 0;
    ASSERT_TRUE(walk.sample_conductor(wo, perfect, rng, &wi, &weight, &order)) << "walk " << k << " did not exit";
    ASSERT_EQ(weight, Rgb(1.0f));
    ASSERT_GT(wi.z, 0.0f);
    ASSERT_NEAR(glm::length(wi), 1.0f, 1e-4f);
    orders += order;
  }

  // VNDF directions fit the single-scattering lobe, cosine ones the broad multiple-scattering lobe.
  const float p_vndf = std::sqrt(c.ax * c.ay) < 0.5f ? 0.8f : 0.5f;
  const Mean albedo =
      integrate_to_furnace_precision([&](int n, Mean& m) { conductor_albedo(walk, wo, perfect, n, p_vndf, rng, m); });
  fmt::print("furnace conductor {} a=({}, {}) theta={:>2}: albedo {:.5f} ± {:.5f} ({} evals), mean order {:.3f}\n",
             name(c.type), c.ax, c.ay, c.theta, albedo.mean(), albedo.se(), albedo.n,
             static_cast<double>(orders) / kWalks);
  EXPECT_NEAR(albedo.mean(), 1.0, 0.01);
  EXPECT_LT(kZ * albedo.se(), 0.01) << "the estimate is too noisy to test the 1% tolerance";
}
INSTANTIATE_TEST_SUITE_P(Cases, ConductorFurnace, ::testing::ValuesIn(furnace_cases()), conductor_case_name);

struct DielectricCase {
  MicrofacetType type;
  float ax, ay;
  float eta;    // n_inside / n_outside
  float theta;  // > 90: wo inside
};
std::string dielectric_case_name(const ::testing::TestParamInfo<DielectricCase>& info) {
  const DielectricCase& c = info.param;
  return fmt::format("{}_a{}x{}_eta{}_theta{}", name(c.type), static_cast<int>(std::lround(c.ax * 100)),
                     static_cast<int>(std::lround(c.ay * 100)), static_cast<int>(std::lround(c.eta * 1000)),
                     static_cast<int>(c.theta));
}

std::vector<DielectricCase> dielectric_furnace_cases() {
  std::vector<DielectricCase> cases;
  for (MicrofacetType t : {MicrofacetType::GGX, MicrofacetType::Beckmann})
    for (float a : {0.2f, 0.7f})
      for (float eta : {1.5f, 1.0f / 1.5f})
        for (float theta : {40.0f, 120.0f})  // 120: inside, beyond the critical angle for eta 1.5
          cases.push_back({t, a, a, eta, theta});
  cases.push_back({MicrofacetType::GGX, 0.15f, 0.6f, 1.5f, 160.0f});
  return cases;
}

class DielectricFurnace : public ::testing::TestWithParam<DielectricCase> {};

// Reflection + transmission of a non-absorbing interface: every walk exits, and in Importance mode (the
// walk density) eval integrates to 1 over the sphere; in Radiance mode the transmitted part is scaled by
// exactly 1/eta_io², tested on the same random numbers.
TEST_P(DielectricFurnace, EnergyIsConserved) {
  const DielectricCase c = GetParam();
  const MicrosurfaceWalk walk(MicrofacetDistribution(c.type, c.ax, c.ay));
  const Vec3 wo = direction(c.theta, 20.0f);
  Pcg32 rng(91 + static_cast<uint64_t>(c.theta) * 3 + static_cast<uint64_t>(c.ax * 1000));

  constexpr int kWalks = 20000;
  int transmitted = 0;
  int64_t orders = 0;
  for (int k = 0; k < kWalks; ++k) {
    Vec3 wi;
    float weight;
    int order = 0;
    ASSERT_TRUE(walk.sample_dielectric(wo, c.eta, TransportMode::Radiance, rng, &wi, &weight, &order));
    const bool transmission = (wi.z > 0.0f) != (wo.z > 0.0f);
    const float eta_io = transmission ? (wi.z < 0.0f ? c.eta : 1.0f / c.eta) : 1.0f;
    ASSERT_FLOAT_EQ(weight, 1.0f / (eta_io * eta_io));
    transmitted += transmission;
    orders += order;
  }

  const float p_lobe = std::sqrt(c.ax * c.ay) < 0.5f ? 0.8f : 0.5f;
  const Mean albedo = integrate_to_furnace_precision(
      [&](int n, Mean& m) { dielectric_albedo(walk, wo, c.eta, TransportMode::Importance, n, p_lobe, rng, m); });
  fmt::print(
      "furnace dielectric {} a=({}, {}) eta={:.4f} theta={:>3}: albedo {:.5f} ± {:.5f} ({} evals), T {:.3f}, "
      "mean order {:.3f}\n",
      name(c.type), c.ax, c.ay, c.eta, c.theta, albedo.mean(), albedo.se(), albedo.n,
      transmitted / static_cast<double>(kWalks), static_cast<double>(orders) / kWalks);
  EXPECT_NEAR(albedo.mean(), 1.0, 0.01);
  EXPECT_LT(kZ * albedo.se(), 0.01);

  // Radiance = Importance / eta_io² for transmission, equal for reflection (same random numbers).
  for (int k = 0; k < 200; ++k) {
    const Vec3 wi = square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
    Pcg32 r1(k), r2(k);
    const float importance = walk.eval_dielectric(wo, wi, c.eta, TransportMode::Importance, r1);
    const float radiance = walk.eval_dielectric(wo, wi, c.eta, TransportMode::Radiance, r2);
    const bool transmission = (wi.z > 0.0f) != (wo.z > 0.0f);
    const float eta_io = transmission ? (wi.z < 0.0f ? c.eta : 1.0f / c.eta) : 1.0f;
    EXPECT_NEAR(radiance, importance / (eta_io * eta_io), 1e-5f * std::max(1.0f, importance));
  }
}
INSTANTIATE_TEST_SUITE_P(Cases, DielectricFurnace, ::testing::ValuesIn(dielectric_furnace_cases()),
                         dielectric_case_name);

// ---------------------------------------------------------------------------------------------------
// Single scattering: with set_max_order(1), eval is the closed-form microfacet BSDF. The walk evaluates
// order 1 in closed form (the exact expectation of its first next-event estimate), so repeated
// evaluations agree to float rounding: the mean of 4 is compared at a 2e-4 relative tolerance (the
// standard error is 0). The stochastic side of single scattering, the walk's height sampling, is tested
// by the SampleMatchesEval rows with max order 1 and by the energy table.

TEST(MicrosurfaceWalkSingle, ConductorMatchesClosedForm) {
  Pcg32 rng(3);
  for (MicrofacetType t : {MicrofacetType::GGX, MicrofacetType::Beckmann}) {
    for (Vec2 a : {Vec2(0.1f), Vec2(0.5f), Vec2(1.0f), Vec2(0.2f, 0.7f)}) {
      MicrosurfaceWalk walk(MicrofacetDistribution(t, a.x, a.y));
      walk.set_max_order(1);
      const ConductorFresnel perfect;
      for (int k = 0; k < 300; ++k) {
        const Vec3 wo = square_to_cosine_hemisphere(Vec2(rng.next_float(), rng.next_float()));
        const Vec3 wi = square_to_uniform_hemisphere(Vec2(rng.next_float(), rng.next_float()));
        double sum = 0;
        for (int r = 0; r < 4; ++r) sum += walk.eval_conductor(wo, wi, perfect, rng).g;
        const double expected = single_conductor(walk.distribution(), wo, wi);
        EXPECT_NEAR(sum / 4, expected, 2e-4 * expected + 1e-7) << name(t) << " " << a.x << "," << a.y;
        // Two-sided: mirrored directions give the same value; opposite hemispheres give 0.
        const Vec3 mo(wo.x, wo.y, -wo.z), mi(wi.x, wi.y, -wi.z);
        EXPECT_NEAR(walk.eval_conductor(mo, mi, perfect, rng).g, expected, 2e-4 * expected + 1e-7);
        EXPECT_EQ(walk.eval_conductor(wo, mi, perfect, rng), Rgb(0.0f));
      }
    }
  }
}

TEST(MicrosurfaceWalkSingle, ConductorFresnelPerBounce) {
  const MetalIor* gold = find_metal("gold");
  ASSERT_NE(gold, nullptr);
  ConductorFresnel F;
  F.perfect = false;
  F.eta = gold->eta;
  F.k = gold->k;
  MicrosurfaceWalk walk(MicrofacetDistribution(MicrofacetType::GGX, 0.4f, 0.4f));
  walk.set_max_order(1);
  Pcg32 rng(4);
  for (int k = 0; k < 300; ++k) {
    const Vec3 wo = square_to_cosine_hemisphere(Vec2(rng.next_float(), rng.next_float()));
    const Vec3 wi = square_to_uniform_hemisphere(Vec2(rng.next_float(), rng.next_float()));
    const Vec3 h = glm::normalize(wo + wi);
    const Rgb expected = fresnel_conductor(glm::dot(wo, h), gold->eta, gold->k) *
                         static_cast<float>(single_conductor(walk.distribution(), wo, wi));
    const Rgb got = walk.eval_conductor(wo, wi, F, rng);
    for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(got[ch], expected[ch], 2e-4f * expected[ch] + 1e-7f);
  }
}

TEST(MicrosurfaceWalkSingle, DielectricMatchesClosedForm) {
  Pcg32 rng(5);
  for (MicrofacetType t : {MicrofacetType::GGX, MicrofacetType::Beckmann}) {
    for (Vec2 a : {Vec2(0.1f), Vec2(0.5f), Vec2(1.0f), Vec2(0.2f, 0.7f)}) {
      for (float eta : {1.5f, 1.0f / 1.33f}) {
        MicrosurfaceWalk walk(MicrofacetDistribution(t, a.x, a.y));
        walk.set_max_order(1);
        int transmissions = 0;
        for (int k = 0; k < 400; ++k) {
          const Vec3 wo = square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
          Vec3 wi = square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
          if (k % 2 == 0) {
            // Half of the pairs in the transmission lobe: refract wo through a visible normal.
            const float s = wo.z > 0.0f ? 1.0f : -1.0f;
            const Vec3 up(wo.x, wo.y, s * wo.z);
            Vec3 w;
            const Vec3 m = walk.distribution().sample_visible(up, Vec2(rng.next_float(), rng.next_float()));
            if (refract(up, m, s > 0.0f ? eta : 1.0f / eta, &w)) wi = glm::normalize(Vec3(w.x, w.y, s * w.z));
          }
          const double expected = single_dielectric_importance(walk.distribution(), wo, wi, eta);
          const bool transmission = (wo.z > 0.0f) != (wi.z > 0.0f);
          const float eta_io = transmission ? (wi.z < 0.0f ? eta : 1.0f / eta) : 1.0f;
          transmissions += transmission && expected > 0.0;
          double sum = 0;
          for (int r = 0; r < 4; ++r) sum += walk.eval_dielectric(wo, wi, eta, TransportMode::Importance, rng);
          EXPECT_NEAR(sum / 4, expected, 2e-4 * expected + 1e-7)
              << name(t) << " eta " << eta << " wo " << wo.x << "," << wo.y << "," << wo.z << " wi " << wi.x << ","
              << wi.y << "," << wi.z;
          const double radiance = walk.eval_dielectric(wo, wi, eta, TransportMode::Radiance, rng);
          EXPECT_NEAR(radiance, expected / sqr(eta_io), (2e-4 * expected + 1e-7) / sqr(eta_io));
        }
        EXPECT_GT(transmissions, 100);  // the transmission branch was exercised
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------------
// Sample/eval consistency: a two-sample chi-square between the histogram of the walk's samples and the
// integral of eval over each cell, both noisy.
//
// Cells: theta_bins × phi_bins of equal solid angle (uniform in cos θ and φ), plus a cell for failed walks.
// Observed O_b = Σ weights / N over the N samples in cell b. Expected E_b = ∫_b eval dω, estimated from
// `evals` stochastic evaluations at directions uniform in the cell: E_b = A_b mean(eval), with variance
// Var(A_b eval) / evals (it contains both the eval noise and the variation over the cell). With every
// weight 1, O_b's variance is Pearson's E_b / N (multinomial); with weights, the sample variance. The
// failed-walk cell expects 1 − Σ E_b. Cells expecting fewer than 30 samples are pooled. Under the null
// hypothesis Σ (O_b − E_b)² / (Var O_b + Var E_b) is asymptotically chi-square with as many degrees of
// freedom as cells (conservative by at most one: the multinomial constraint).
struct TwoSampleOptions {
  int theta_bins = 12, phi_bins = 24;
  double cos_min = -1.0, cos_max = 1.0;  // samples outside fail the test if eval is zero there
  int samples = 400'000;
  int evals = 200;  // per cell
  bool weighted = false;
  uint64_t seed = 1;
};

struct TwoSampleResult {
  bool passed = false;
  double statistic = 0, p_value = 0, threshold = 0;
  int dof = 0;
  std::string message;
};

using WalkSampler = std::function<bool(Pcg32&, Vec3*, double*)>;  // false: the walk failed
using WalkEval = std::function<double(const Vec3&, Pcg32&)>;

TwoSampleResult sample_eval_chi2(const WalkSampler& sample, const WalkEval& eval, const TwoSampleOptions& opt) {
  const int cells = opt.theta_bins * opt.phi_bins;
  const double dcos = (opt.cos_max - opt.cos_min) / opt.theta_bins, dphi = 2.0 * kPi / opt.phi_bins;
  std::vector<double> obs(cells + 1, 0.0), obs2(cells + 1, 0.0);
  int64_t outside = 0;
  Pcg32 rng(opt.seed);
  for (int k = 0; k < opt.samples; ++k) {
    Vec3 w;
    double weight = 1.0;
    if (!sample(rng, &w, &weight)) {
      obs[cells] += 1.0;
      obs2[cells] += 1.0;
      continue;
    }
    const double z = std::clamp(static_cast<double>(w.z), -1.0, 1.0);
    if (z < opt.cos_min || z > opt.cos_max) {
      ++outside;
      continue;
    }
    double phi = std::atan2(w.y, w.x);
    if (phi < 0) phi += 2.0 * kPi;
    const int it = std::min(static_cast<int>((z - opt.cos_min) / dcos), opt.theta_bins - 1);
    const int ip = std::min(static_cast<int>(phi / dphi), opt.phi_bins - 1);
    obs[it * opt.phi_bins + ip] += weight;
    obs2[it * opt.phi_bins + ip] += weight * weight;
  }
  const double n = opt.samples;
  std::vector<double> expected(cells + 1, 0.0), var_expected(cells + 1, 0.0);
  double total = 0, total_var = 0;
  for (int it = 0; it < opt.theta_bins; ++it) {
    for (int ip = 0; ip < opt.phi_bins; ++ip) {
      Mean m;
      for (int k = 0; k < opt.evals; ++k) {
        const double z = opt.cos_min + (it + rng.next_double()) * dcos;
        const double phi = (ip + rng.next_double()) * dphi;
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        const Vec3 w(static_cast<float>(r * std::cos(phi)), static_cast<float>(r * std::sin(phi)),
                     static_cast<float>(z));
        m.add(eval(w, rng) * dcos * dphi);
      }
      const int c = it * opt.phi_bins + ip;
      expected[c] = m.mean();
      var_expected[c] = sqr(m.se());
      total += expected[c];
      total_var += var_expected[c];
    }
  }
  expected[cells] = opt.weighted ? 0.0 : std::max(0.0, 1.0 - total);
  var_expected[cells] = opt.weighted ? 0.0 : total_var;

  TwoSampleResult res;
  if (outside > 0) {
    res.message = fmt::format("{} samples outside the binned range", outside);
    return res;
  }
  auto obs_var = [&](int c) {
    if (!opt.weighted) return expected[c] / n;
    return std::max(obs2[c] / n - sqr(obs[c] / n), 0.0) / n;
  };
  struct Cell {
    double o, e, v;
    int index;
  };
  std::vector<Cell> used;
  Cell pooled{0, 0, 0, -1};
  for (int c = 0; c <= cells; ++c) {
    const Cell cell{obs[c] / n, expected[c], obs_var(c) + var_expected[c], c};
    if (cell.e * n < 30.0) {
      pooled.o += cell.o;
      pooled.e += cell.e;
      pooled.v += cell.v;
    } else {
      used.push_back(cell);
    }
  }
  if (pooled.o > 0.0 || pooled.e > 0.0) {
    if (!opt.weighted) pooled.v = std::max(pooled.v, pooled.e / n);  // Pearson's term for the pooled count
    if (pooled.v <= 0.0) {
      res.message = fmt::format("samples (mass {:.3g}) where eval is zero", pooled.o);
      return res;
    }
    used.push_back(pooled);
  }
  std::vector<std::pair<double, int>> terms;
  for (const Cell& c : used) {
    const double t = sqr(c.o - c.e) / c.v;
    res.statistic += t;
    terms.emplace_back(t, c.index);
  }
  res.dof = static_cast<int>(used.size());
  res.p_value = chi2_survival(res.statistic, res.dof);
  res.threshold = 1.0 - std::pow(1.0 - 0.01, 1.0 / kChi2Family);
  res.passed = res.p_value >= res.threshold;
  std::sort(terms.rbegin(), terms.rend());
  res.message =
      fmt::format("chi2 {:.1f}, dof {}, p {:.4f} (threshold {:.2e}); ∫eval {:.5f} ± {:.5f}; failed walks {}",
                  res.statistic, res.dof, res.p_value, res.threshold, total, std::sqrt(total_var), obs[cells]);
  for (size_t k = 0; k < std::min<size_t>(terms.size(), res.passed ? 0 : 5); ++k) {
    const int c = terms[k].second;
    if (c < 0) {
      res.message += fmt::format("\n  pooled cell: {:.1f}", terms[k].first);
      continue;
    }
    res.message += fmt::format(
        "\n  cell {} (theta bin {}, phi bin {}): observed {:.6f} expected {:.6f} ± {:.6f}, "
        "term {:.1f}",
        c, c / opt.phi_bins, c % opt.phi_bins, obs[c] / n, expected[c], std::sqrt(var_expected[c]), terms[k].first);
  }
  return res;
}

struct ConsistencyCase {
  const char* label;
  bool dielectric;
  MicrofacetType type;
  float ax, ay;
  float theta;
  float eta;          // dielectric
  const char* metal;  // conductor: nullptr = perfect
  int max_order;      // 0 = unbounded
};
class SampleMatchesEval : public ::testing::TestWithParam<ConsistencyCase> {};

TEST_P(SampleMatchesEval, TwoSampleChi2) {
  const ConsistencyCase c = GetParam();
  MicrosurfaceWalk walk(MicrofacetDistribution(c.type, c.ax, c.ay));
  walk.set_max_order(c.max_order);
  const Vec3 wo = direction(c.theta, 35.0f);
  ConductorFresnel F;
  if (c.metal) {
    const MetalIor* m = find_metal(c.metal);
    ASSERT_NE(m, nullptr);
    F.perfect = false;
    F.eta = m->eta;
    F.k = m->k;
  }
  TwoSampleOptions opt;
  opt.weighted = c.metal != nullptr;
  opt.seed = 1234 + static_cast<uint64_t>(c.theta);
  if (!c.dielectric) {
    opt.cos_min = 0.0;
    opt.theta_bins = 10;
    opt.phi_bins = 20;
  }
  const int channel = 2;  // blue: gold's lowest Fresnel reflectance
  WalkSampler sample;
  WalkEval eval;
  if (c.dielectric) {
    sample = [&](Pcg32& rng, Vec3* wi, double* weight) {
      float w;
      const bool ok = walk.sample_dielectric(wo, c.eta, TransportMode::Importance, rng, wi, &w);
      *weight = w;
      return ok;
    };
    eval = [&](const Vec3& wi, Pcg32& rng) {
      return static_cast<double>(walk.eval_dielectric(wo, wi, c.eta, TransportMode::Importance, rng));
    };
  } else {
    sample = [&](Pcg32& rng, Vec3* wi, double* weight) {
      Rgb w;
      const bool ok = walk.sample_conductor(wo, F, rng, wi, &w);
      *weight = w[channel];
      return ok;
    };
    eval = [&](const Vec3& wi, Pcg32& rng) {
      return static_cast<double>(walk.eval_conductor(wo, wi, F, rng)[channel]);
    };
  }
  const TwoSampleResult r = sample_eval_chi2(sample, eval, opt);
  fmt::print("sample/eval {}: {}\n", c.label, r.message);
  EXPECT_TRUE(r.passed) << r.message;
}
INSTANTIATE_TEST_SUITE_P(
    Cases, SampleMatchesEval,
    ::testing::Values(ConsistencyCase{"conductor_GGX_a30_theta45", false, MicrofacetType::GGX, 0.3f, 0.3f, 45.0f, 1.0f,
                                      nullptr, 0},
                      ConsistencyCase{"conductor_Beckmann_a100_theta75", false, MicrofacetType::Beckmann, 1.0f, 1.0f,
                                      75.0f, 1.0f, nullptr, 0},
                      ConsistencyCase{"conductor_GGX_a20x80_theta60", false, MicrofacetType::GGX, 0.2f, 0.8f, 60.0f,
                                      1.0f, nullptr, 0},
                      ConsistencyCase{"conductor_Beckmann_a60_theta0", false, MicrofacetType::Beckmann, 0.6f, 0.6f,
                                      0.0f, 1.0f, nullptr, 0},
                      ConsistencyCase{"conductor_gold_GGX_a80_theta30", false, MicrofacetType::GGX, 0.8f, 0.8f, 30.0f,
                                      1.0f, "gold", 0},
                      ConsistencyCase{"conductor_single_GGX_a80_theta60", false, MicrofacetType::GGX, 0.8f, 0.8f, 60.0f,
                                      1.0f, nullptr, 1},
                      ConsistencyCase{"dielectric_GGX_a50_eta150_theta40", true, MicrofacetType::GGX, 0.5f, 0.5f, 40.0f,
                                      1.5f, nullptr, 0},
                      ConsistencyCase{"dielectric_Beckmann_a50_eta150_theta150", true, MicrofacetType::Beckmann, 0.5f,
                                      0.5f, 150.0f, 1.5f, nullptr, 0},
                      ConsistencyCase{"dielectric_GGX_a80_eta150_theta120", true, MicrofacetType::GGX, 0.8f, 0.8f,
                                      120.0f, 1.5f, nullptr, 0},
                      ConsistencyCase{"dielectric_Beckmann_a30x90_eta067_theta70", true, MicrofacetType::Beckmann, 0.3f,
                                      0.9f, 70.0f, 1.0f / 1.5f, nullptr, 0},
                      ConsistencyCase{"dielectric_single_Beckmann_a70_eta150_theta50", true, MicrofacetType::Beckmann,
                                      0.7f, 0.7f, 50.0f, 1.5f, nullptr, 1}),
    [](const ::testing::TestParamInfo<ConsistencyCase>& p) { return std::string(p.param.label); });

// ---------------------------------------------------------------------------------------------------
// Reciprocity on average. eval includes |cos θi|, so f(wo, wi) = f(wi, wo) reads
// eval(wo, wi) / |cos θi| = eval(wi, wo) / |cos θo|; for a dielectric transmission (Radiance mode) the
// generalised form is eval(wo, wi) / (|cos θi| η_o²) = eval(wi, wo) / (|cos θo| η_i²) (Veach 1997 §5.2).
// The forward (one-walk) estimator is used as well as the bidirectional one: the bidirectional estimator
// is symmetric by construction, the forward one only if the walk itself is reciprocal.

struct ReciprocityCase {
  bool dielectric;
  MicrofacetType type;
  float alpha;
  float theta_a, phi_a, theta_b, phi_b;
  float eta;
  bool gold;
};
class Reciprocity : public ::testing::TestWithParam<ReciprocityCase> {};

TEST_P(Reciprocity, MeansAgree) {
  const ReciprocityCase c = GetParam();
  const Vec3 a = direction(c.theta_a, c.phi_a), b = direction(c.theta_b, c.phi_b);
  ConductorFresnel F;
  if (c.gold) {
    const MetalIor* gold = find_metal("gold");
    F.perfect = false;
    F.eta = gold->eta;
    F.k = gold->k;
  }
  auto ior = [&](const Vec3& w) { return w.z > 0.0f ? 1.0 : static_cast<double>(c.eta); };
  for (bool bidirectional : {false, true}) {
    MicrosurfaceWalk walk(MicrofacetDistribution(c.type, c.alpha, c.alpha));
    walk.set_bidirectional(bidirectional);
    Pcg32 rng(77);
    Mean ab, ba;
    constexpr int kN = 30000;
    for (int k = 0; k < kN; ++k) {
      if (c.dielectric) {
        ab.add(walk.eval_dielectric(a, b, c.eta, TransportMode::Radiance, rng) / (std::abs(b.z) * sqr(ior(a))));
        ba.add(walk.eval_dielectric(b, a, c.eta, TransportMode::Radiance, rng) / (std::abs(a.z) * sqr(ior(b))));
      } else {
        ab.add(walk.eval_conductor(a, b, F, rng).b / std::abs(b.z));
        ba.add(walk.eval_conductor(b, a, F, rng).b / std::abs(a.z));
      }
    }
    const double se = std::hypot(ab.se(), ba.se());
    fmt::print("reciprocity {} {} a={} ({},{})<->({},{}){}{}: {:.6f} ± {:.6f} vs {:.6f} ± {:.6f}\n",
               c.dielectric ? "dielectric" : "conductor", name(c.type), c.alpha, c.theta_a, c.phi_a, c.theta_b, c.phi_b,
               c.gold ? " gold" : "", bidirectional ? " (bidirectional)" : " (forward)", ab.mean(), ab.se(), ba.mean(),
               ba.se());
    EXPECT_NEAR(ab.mean(), ba.mean(), kZ * se) << (bidirectional ? "bidirectional" : "forward");
    EXPECT_GT(ab.mean(), 0.0);
  }
}
INSTANTIATE_TEST_SUITE_P(
    Cases, Reciprocity,
    ::testing::Values(ReciprocityCase{false, MicrofacetType::GGX, 1.0f, 70.0f, 0.0f, 20.0f, 100.0f, 1.0f, false},
                      ReciprocityCase{false, MicrofacetType::Beckmann, 0.8f, 60.0f, 40.0f, 30.0f, 190.0f, 1.0f, true},
                      ReciprocityCase{false, MicrofacetType::GGX, 0.5f, 10.0f, 0.0f, 85.0f, 180.0f, 1.0f, false},
                      // dielectric transmission both ways, and reflection inside (total internal reflection)
                      ReciprocityCase{true, MicrofacetType::GGX, 0.7f, 30.0f, 0.0f, 140.0f, 200.0f, 1.5f, false},
                      ReciprocityCase{true, MicrofacetType::Beckmann, 0.6f, 75.0f, 60.0f, 140.0f, 250.0f, 1.5f, false},
                      ReciprocityCase{true, MicrofacetType::GGX, 0.9f, 125.0f, 0.0f, 160.0f, 120.0f, 1.5f, false},
                      ReciprocityCase{true, MicrofacetType::GGX, 0.6f, 50.0f, 0.0f, 20.0f, 150.0f, 1.5f, false}));

// ---------------------------------------------------------------------------------------------------
// The bidirectional (MIS) estimator and the forward walk estimate the same value; prints their variance
// and cost per evaluation.

TEST(MicrosurfaceWalkEstimators, BidirectionalAgreesWithForward) {
  struct Pair {
    bool dielectric;
    MicrofacetType type;
    float alpha;
    Vec3 wo, wi;
  };
  const Pair pairs[] = {
      {false, MicrofacetType::GGX, 0.2f, direction(60, 0), direction(40, 150)},
      {false, MicrofacetType::GGX, 1.0f, direction(60, 0), direction(60, 180)},
      {false, MicrofacetType::Beckmann, 0.5f, direction(80, 0), direction(30, 90)},
      {true, MicrofacetType::GGX, 0.2f, direction(30, 0), direction(150, 190)},
      {true, MicrofacetType::GGX, 0.6f, direction(130, 0), direction(120, 170)},
      {true, MicrofacetType::Beckmann, 0.6f, direction(60, 0), direction(20, 120)},
  };
  const ConductorFresnel perfect;
  for (const Pair& p : pairs) {
    Mean est[2];
    double seconds[2];
    for (int mode = 0; mode < 2; ++mode) {
      MicrosurfaceWalk walk(MicrofacetDistribution(p.type, p.alpha, p.alpha));
      walk.set_bidirectional(mode == 1);
      Pcg32 rng(100 + mode);
      const auto t0 = std::chrono::steady_clock::now();
      for (int k = 0; k < 40000; ++k)
        est[mode].add(p.dielectric ? walk.eval_dielectric(p.wo, p.wi, 1.5f, TransportMode::Importance, rng)
                                   : walk.eval_conductor(p.wo, p.wi, perfect, rng).g);
      seconds[mode] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / 40000;
    }
    fmt::print(
        "estimators {} {} a={}: forward {:.6f} (sd {:.4f}, {:.2f} us)  bidirectional {:.6f} (sd {:.4f}, {:.2f} us)\n",
        p.dielectric ? "dielectric" : "conductor", name(p.type), p.alpha, est[0].mean(),
        est[0].se() * std::sqrt(est[0].n), seconds[0] * 1e6, est[1].mean(), est[1].se() * std::sqrt(est[1].n),
        seconds[1] * 1e6);
    EXPECT_NEAR(est[0].mean(), est[1].mean(), kZ * std::hypot(est[0].se(), est[1].se()));
  }
}

// ---------------------------------------------------------------------------------------------------
// The order cap (kMaxOrder = 256, counted as absorption) is never reached in practice: the distribution of
// the number of bounces has a geometric tail; its measured decay per bounce puts P(order > 256) far below
// float resolution. Worst cases: the roughest conductor at normal incidence, and rough glass seen from
// inside beyond the critical angle (total internal reflection keeps the walk on the microsurface).

TEST(MicrosurfaceWalkOrders, CapIsNeverReached) {
  struct Case {
    const char* label;
    bool dielectric;
    MicrofacetType type;
    float alpha, theta, eta;
  };
  const Case cases[] = {{"conductor GGX a=1 theta=0", false, MicrofacetType::GGX, 1.0f, 0.0f, 1.0f},
                        {"conductor Beckmann a=1 theta=0", false, MicrofacetType::Beckmann, 1.0f, 0.0f, 1.0f},
                        {"dielectric GGX a=1 eta=1.5 theta=120", true, MicrofacetType::GGX, 1.0f, 120.0f, 1.5f},
                        {"dielectric GGX a=1 eta=1.5 theta=30", true, MicrofacetType::GGX, 1.0f, 30.0f, 1.5f}};
  for (const Case& c : cases) {
    const MicrosurfaceWalk walk(MicrofacetDistribution(c.type, c.alpha, c.alpha));
    const Vec3 wo = direction(c.theta, 0.0f);
    Pcg32 rng(2024);
    constexpr int kN = 300'000;
    std::vector<int64_t> tail(MicrosurfaceWalk::kMaxOrder + 2, 0);  // tail[k] = #walks with order >= k
    int failed = 0;
    double orders = 0;
    for (int k = 0; k < kN; ++k) {
      Vec3 wi;
      int order = 0;
      bool ok;
      if (c.dielectric) {
        float w;
        ok = walk.sample_dielectric(wo, c.eta, TransportMode::Importance, rng, &wi, &w, &order);
      } else {
        Rgb w;
        ok = walk.sample_conductor(wo, ConductorFresnel{}, rng, &wi, &w, &order);
      }
      failed += !ok;
      orders += order;
      for (int j = 0; j <= std::min(order, MicrosurfaceWalk::kMaxOrder + 1); ++j) ++tail[j];
    }
    // Decay of the tail per bounce, from P(order >= 2) to the last order with at least 100 walks.
    int last = 3;
    while (last + 1 < static_cast<int>(tail.size()) && tail[last + 1] >= 100) ++last;
    ASSERT_GE(tail[last], 100);
    const double decay = std::pow(static_cast<double>(tail[last]) / tail[2], 1.0 / (last - 2));
    const double log10_p_cap =
        std::log10(tail[last] / static_cast<double>(kN)) + (MicrosurfaceWalk::kMaxOrder + 1 - last) * std::log10(decay);
    int max_order = 0;
    for (int j = 0; j < static_cast<int>(tail.size()); ++j)
      if (tail[j] > 0) max_order = j;
    fmt::print(
        "orders {}: mean {:.3f}, P(>=2) {:.4f}, P(>=4) {:.2e}, max {}, tail decay {:.3f}/bounce, "
        "extrapolated P(order > 256) = 1e{:.0f}\n",
        c.label, orders / kN, tail[2] / static_cast<double>(kN), tail[4] / static_cast<double>(kN), max_order, decay,
        log10_p_cap);
    EXPECT_EQ(failed, 0);
    EXPECT_LT(max_order, 64);
    EXPECT_LT(log10_p_cap, -30.0);
  }
}

// ---------------------------------------------------------------------------------------------------
// Energy table: directional albedo of single scattering (closed form, and the walk cut at order 1)
// against all orders (the walk), conductor with F = 1.

struct EnergyRow {
  double single_closed = 0, single_closed_se = 0;  // ∫ D G2 / (4 cos θo) dωi, VNDF-sampled
  double single_walk = 0, single_walk_se = 0;      // fraction of walks that leave after one bounce
  double total_walk = 0;                           // fraction of walks that leave at all
  double mean_order = 0;                           // scattering events per sample
  int max_order_seen = 0;
};

EnergyRow energy_row(MicrofacetType type, float alpha, float theta_deg, int n, uint64_t seed) {
  const MicrofacetDistribution d(type, alpha, alpha);
  const Vec3 wo = direction(theta_deg, 0.0f);
  Pcg32 rng(seed);
  EnergyRow row;
  // Closed form: with m ~ D_wo and wi = reflect(wo, m), D G2 / (4 cos θo) / pdf = G2 / G1(wo).
  Mean closed;
  for (int k = 0; k < n; ++k) {
    const Vec3 wi = reflect(wo, d.sample_visible(wo, Vec2(rng.next_float(), rng.next_float())));
    closed.add(wi.z > 0.0f ? (1.0 + d.lambda(wo)) / (1.0 + d.lambda(wo) + d.lambda(wi)) : 0.0);
  }
  row.single_closed = closed.mean();
  row.single_closed_se = closed.se();
  const ConductorFresnel perfect;
  MicrosurfaceWalk single(d);
  single.set_max_order(1);
  Mean exits;
  for (int k = 0; k < n; ++k) {
    Vec3 wi;
    Rgb w;
    exits.add(single.sample_conductor(wo, perfect, rng, &wi, &w) ? 1.0 : 0.0);
  }
  row.single_walk = exits.mean();
  row.single_walk_se = exits.se();
  const MicrosurfaceWalk all(d);
  int64_t ok = 0, orders = 0;
  for (int k = 0; k < n; ++k) {
    Vec3 wi;
    Rgb w;
    int order = 0;
    if (all.sample_conductor(wo, perfect, rng, &wi, &w, &order)) ++ok;
    orders += order;
    row.max_order_seen = std::max(row.max_order_seen, order);
  }
  row.total_walk = ok / static_cast<double>(n);
  row.mean_order = orders / static_cast<double>(n);
  return row;
}

TEST(MicrosurfaceWalkEnergy, SingleVersusMultipleScatteringTable) {
  const float thetas[] = {0.0f, 45.0f, 75.0f};
  for (MicrofacetType type : {MicrofacetType::GGX, MicrofacetType::Beckmann}) {
    fmt::print(
        "\nDirectional albedo, conductor F = 1, {}: single scattering E1 and multiple scattering 1 - E1 "
        "(all orders sum to the walk's total)\n",
        name(type));
    fmt::print("{:>5} |", "alpha");
    for (float t : thetas) fmt::print(" theta_o={:>2}: {:>7} {:>7} {:>7} {:>6} |", t, "E1", "E1walk", "multi", "order");
    fmt::print("\n");
    double previous[3] = {2, 2, 2};
    for (int ia = 1; ia <= 10; ++ia) {
      const float alpha = 0.1f * ia;
      fmt::print("{:>5.1f} |", alpha);
      for (int it = 0; it < 3; ++it) {
        const EnergyRow r = energy_row(type, alpha, thetas[it], 50'000, 1000 + ia * 10 + it);
        fmt::print("             {:.4f} {:.4f} {:.4f} {:>6.3f} |", r.single_closed, r.single_walk,
                   r.total_walk - r.single_closed, r.mean_order);
        // The walk cut at one bounce leaves with the closed-form single-scattering probability.
        EXPECT_NEAR(r.single_walk, r.single_closed, kZ * std::hypot(r.single_walk_se, r.single_closed_se))
            << name(type) << " alpha " << alpha << " theta " << thetas[it];
        EXPECT_EQ(r.total_walk, 1.0);  // no walk reached the order cap
        EXPECT_LT(r.max_order_seen, MicrosurfaceWalk::kMaxOrder / 4);
        // Rougher loses more to multiple scattering (not at grazing incidence, where Beckmann's E1 has a
        // shallow minimum near alpha = 0.3, confirmed by quadrature).
        if (thetas[it] < 60.0f) {
          EXPECT_LE(r.single_closed, previous[it] + 1e-3);
        }
        previous[it] = r.single_closed;
      }
      fmt::print("\n");
    }
  }
}

}  // namespace
}  // namespace kozu::test
