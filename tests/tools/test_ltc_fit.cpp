// The LTC fitter (tools/ltc_fit.h) and its minimiser (tools/nelder_mead.h): Nelder–Mead finds Rosenbrock's minimum;
// the fitter recovers the matrix of a lobe that is itself an LTC; GGX entries fit with small L1 errors.
#include "tools/ltc_fit.h"

#include "core/arena.h"
#include "core/ltc.h"
#include "materials/conductor.h"
#include "materials/ltc_table.h"
#include "materials/microfacet_albedo.h"
#include "tools/nelder_mead.h"

#include "support/sanitizer.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <tuple>
#include <vector>

namespace kozu::test {
namespace {

TEST(NelderMead, FindsRosenbrocksMinimum) {
  const auto rosenbrock = [](const std::vector<double>& x) {
    return 100.0 * (x[1] - x[0] * x[0]) * (x[1] - x[0] * x[0]) + (1.0 - x[0]) * (1.0 - x[0]);
  };
  NelderMeadOptions o;
  o.tolerance = 1e-14;
  o.max_evaluations = 5000;
  const NelderMeadResult r = nelder_mead(rosenbrock, {-1.2, 1.0}, o);
  EXPECT_NEAR(r.x[0], 1.0, 1e-4);
  EXPECT_NEAR(r.x[1], 1.0, 1e-4);
  EXPECT_LT(r.value, 1e-8);
}

// A BSDF whose cosine-weighted lobe is k D for an LTC D that lies in the upper hemisphere (d = 0 in eq. 6).
class LtcLobe final : public Bsdf {
 public:
  LtcLobe(const Ltc& d, float k) : d_(d), k_(k) {}
  Rgb eval(const Vec3&, const Vec3& wi, TransportMode) const override { return Rgb(k_ * d_.eval(wi)); }
  BsdfSample sample(const Vec3& wo, float, const Vec2& u, TransportMode mode) const override {
    BsdfSample s;
    s.wi = d_.sample(u);
    s.pdf = d_.pdf(s.wi);
    s.f = eval(wo, s.wi, mode);
    s.flags = kBsdfReflection | kBsdfGlossy;
    return s;
  }
  float pdf(const Vec3&, const Vec3& wi) const override { return d_.pdf(wi); }
  uint32_t flags() const override { return kBsdfReflection | kBsdfGlossy; }

 private:
  Ltc d_;
  float k_;
};

TEST(LtcFit, RecoversAnLtcLobe) {
  LtcFitEntry truth;
  truth.a = 0.3f, truth.b = 0.4f, truth.c = 0.5f, truth.d = 0.0f;
  const LtcLobe lobe(Ltc(truth.m()), 0.7f);
  LtcFitEntry start;  // the clamped cosine, sheared a little
  start.d = 0.05f;
  const LtcFitEntry e = fit_ltc_entry(lobe, Vec3(0, 0, 1), start, LtcFitOptions{});
  std::printf("fitted a %.5f b %.5f c %.5f d %.5f, norm %.5f, L1 error %.2e\n", e.a, e.b, e.c, e.d, e.norm, e.error);
  EXPECT_NEAR(e.a, truth.a, 2e-3 * truth.a);
  EXPECT_NEAR(e.b, truth.b, 2e-3);
  EXPECT_NEAR(e.c, truth.c, 2e-3 * truth.c);
  EXPECT_NEAR(e.d, truth.d, 2e-3);
  EXPECT_NEAR(e.norm, 0.7f, 1e-3);
  EXPECT_LT(e.error, 5e-3);
}

// GGX (a rough conductor with F = 1, single scattering) at a few entries, fitted down from α = 1 as the table is:
// every fit must improve on the entry it starts from (the previous α's). The L1 errors are printed (docs/lights.md):
// small near normal view, larger at grazing angles, where the horizon cuts the lobe and the L³ error Heitz et al. 2016
// minimise favours the peak over the tail.
TEST(LtcFit, GgxEntries) {
  const ConductorFresnel fresnel;
  const LtcFitOptions o;
  for (float theta_deg : {0.0f, 45.0f, 75.0f}) {
    const float theta = theta_deg * kPi / 180.0f;
    const Vec3 wv(std::sin(theta), 0.0f, std::cos(theta));
    LtcFitEntry start;
    start.b = 0.5f * std::tan(0.5f * theta);
    std::string line = fmt::format("theta {:2.0f}:", theta_deg);
    for (float alpha : {1.0f, 0.5f, 0.25f, 0.1f}) {
      const RoughConductorBsdf ggx(MicrofacetDistribution(MicrofacetType::GGX, alpha, alpha), &fresnel, nullptr);
      const LtcFitEntry e = fit_ltc_entry(ggx, wv, start, o);
      const float before = ltc_fit_error(ggx, wv, start, o.report_samples);
      line += fmt::format("  a{:.2f}: L1 {:.4f} (start {:.4f}) n {:.4f}", alpha, e.error, before, e.norm);
      EXPECT_LT(e.error, before) << "theta " << theta_deg << " alpha " << alpha;
      // The norm is the lobe's directional albedo, by the albedo tables' own quadrature (microfacet_albedo.h).
      const double albedo =
          albedo::integrate_conductor(MicrofacetDistribution(MicrofacetType::GGX, alpha, alpha), wv.z, 256);
      EXPECT_NEAR(e.norm, albedo, 1e-3) << "theta " << theta_deg;
      start = e;
    }
    std::printf("%s\n", line.c_str());
  }
}

TEST(LtcFit, CheckedInTablesAreTheFittersAndMatchTheBrdf) {
  // src/materials/ltc_<brdf>_data.inc (kozu fit-ltc), all six: every 17th entry's stored L1 error and norm recomputed
  // from its stored M⁻¹ against kozu's BRDF; the lookup returns the entry at grid points; the error distribution
  // printed.
  for (const LtcBrdf brdf : kLtcBrdfs) {
    const char* name = ltc_brdf_name(brdf);
    const LtcTargetBsdf target = ltc_target(brdf, kLtcTableSize);
    std::vector<float> errors;
    for (int i = 0; i < kLtcTableSize; ++i)
      for (int j = 0; j < kLtcTableSize; ++j) errors.push_back(ltc_table_entry(brdf, i, j).error);
    for (int n = 0; n < kLtcTableSize * kLtcTableSize; n += kSanitized ? 97 : 17) {
      const int i = n / kLtcTableSize, j = n % kLtcTableSize;
      const LtcTableEntry& t = ltc_table_entry(brdf, i, j);
      const float alpha = ltc_table_alpha(i, kLtcTableSize), theta = ltc_table_theta(j, kLtcTableSize);
      const Vec3 wv(std::sin(theta), 0.0f, std::cos(theta));
      LtcFitEntry e;  // M from the stored M⁻¹ (eq. 6 form: a, b, c, d with M₂₂ = 1 after normalising)
      Mat3 m_inv(0.0f);
      m_inv[0][0] = t.m00;
      m_inv[2][0] = t.m02;
      m_inv[1][1] = t.m11;
      m_inv[0][2] = t.m20;
      m_inv[2][2] = 1.0f;
      Mat3 m = glm::inverse(m_inv);
      m /= m[2][2];
      e.a = m[0][0];
      e.b = m[2][0];
      e.c = m[1][1];
      e.d = m[0][2];
      Arena arena;
      const Bsdf& bsdf = *target(alpha, arena);
      EXPECT_NEAR(ltc_fit_error(bsdf, wv, e, 256), t.error, 2e-3 + 0.01 * t.error)
          << name << " entry " << i << ", " << j;
      if (theta < 1.5f) {  // at the grazing column the quadrature resolves the norm only to ~1e-2
        // The compensated lobe's norm is 1 to the albedo tables' accuracy (a few 1e-3).
        EXPECT_NEAR(ltc_target_norm(brdf, wv.z, alpha), t.norm, 2e-3) << name << " entry " << i << ", " << j;
      }
      const LtcLobeFit fit = ltc_lookup(brdf, wv.z, alpha);
      // 1e-3: θ_v through cos and acos in float lands a few 1e-5 rad off the node, where the grazing column's
      // norm changes fastest.
      EXPECT_NEAR(fit.norm, t.norm, 1e-3) << name << " lookup at entry " << i << ", " << j;
    }
    std::sort(errors.begin(), errors.end());
    std::printf("%s: L1 fit error median %.4f, 90th percentile %.4f, max %.4f\n", name, errors[errors.size() / 2],
                errors[errors.size() * 9 / 10], errors.back());
  }
}

}  // namespace
}  // namespace kozu::test
