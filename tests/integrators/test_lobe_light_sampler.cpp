// Light samples shaped by a glossy lobe (integrators/lobe_light_sampler.h): the mixture's samples against its own density
// (chi-square over the light's own coordinates, for a quad light and a triangle light, lobes of GGX α 0.08 to 0.32 at
// random views); the density integrates to 1 over the light; which lobes and lights take part; and the variance of
// the direct light of a highlight against sampling the light by area.
#include "integrators/lobe_light_sampler.h"

#include "core/frame.h"
#include "core/rng.h"
#include "materials/conductor.h"
#include "materials/microfacet.h"
#include "support/chi2.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <memory>
#include <vector>

namespace kozu::test {
namespace {

// Three uniform numbers in a fixed order (argument evaluation order is unspecified).
Vec3 next_vec3(Pcg32& rng) {
  const float x = rng.next_float();
  const float y = rng.next_float();
  return Vec3(x, y, rng.next_float());
}

// A rough conductor's LTC lobes (F = 1, compensated) at the view wo, in the local frame.
int conductor_lobes(float alpha, const Vec3& wo, std::array<LtcLobe, kMaxLtcLobes>* lobes) {
  const ConductorFresnel f1;
  const MicrofacetDistribution d(MicrofacetType::GGX, alpha, alpha);
  const ConductorCompensation comp = ConductorCompensation::make(MicrofacetType::GGX, alpha, f1, true);
  const RoughConductorBsdf bsdf(d, &f1, &comp);
  return bsdf.ltc_lobes(wo, Vec3(0.0f, 0.0f, 1.0f), lobes->data());
}

// A parallelogram p0 + a e1 + b e2 ((a, b) ∈ [0, 1]²) as a quad light's mesh, or its lower triangle (a + b <= 1) as a
// triangle light's.
struct FlatLight {
  Vec3 p0, e1, e2;
  std::unique_ptr<TriangleMesh> mesh;
  std::unique_ptr<DiffuseAreaLight> light;
  FlatLight(const Vec3& p0_, const Vec3& e1_, const Vec3& e2_, bool triangle, bool two_sided = true)
      : p0(p0_), e1(e1_), e2(e2_) {
    if (triangle) {
      mesh = std::make_unique<TriangleMesh>(std::vector<Vec3>{p0, p0 + e1, p0 + e2}, std::vector<uint32_t>{0, 1, 2});
      light = std::make_unique<TriangleLight>(mesh.get(), 0, Rgb(1.0f), two_sided);
    } else {
      mesh = std::make_unique<TriangleMesh>(std::vector<Vec3>{p0, p0 + e1, p0 + e1 + e2, p0 + e2},
                                            std::vector<uint32_t>{0, 1, 2, 0, 2, 3});
      light = std::make_unique<PolygonLight>(mesh.get(), Rgb(1.0f), two_sided);
    }
  }
  // The chi-square's coordinates of the point (a, b): (a, b) itself for the parallelogram; for the triangle
  // (u, v) = (a + b, b / (a + b)), so that no cell straddles its diagonal edge.
  Vec2 cell(const Vec2& ab, bool triangle) const {
    if (!triangle) return ab;
    const float u = ab.x + ab.y;
    return Vec2(u, u > 0.0f ? ab.y / u : 0.0f);
  }
  // (a, b) where the ray from the origin along w meets the light's plane.
  Vec2 coordinates(const Vec3& w) const {
    const Vec3d n = glm::cross(Vec3d(e1), Vec3d(e2));
    const double t = glm::dot(n, Vec3d(p0)) / glm::dot(n, Vec3d(w));
    const Vec3d d = t * Vec3d(w) - Vec3d(p0);
    const double a2 = glm::dot(n, n);
    return Vec2(static_cast<float>(glm::dot(glm::cross(d, Vec3d(e2)), n) / a2),
                static_cast<float>(glm::dot(glm::cross(Vec3d(e1), d), n) / a2));
  }
  // The solid-angle density p at the point (a, b) as a density per unit (a, b): p |cos θ_l| |e1 × e2| / r².
  double per_ab(const Vec2& ab, float p) const {
    const Vec3d x = Vec3d(p0) + double(ab.x) * Vec3d(e1) + double(ab.y) * Vec3d(e2);
    const Vec3d n = glm::cross(Vec3d(e1), Vec3d(e2));
    const double r2 = glm::dot(x, x);
    return double(p) * std::abs(glm::dot(n, x)) / (std::sqrt(r2) * r2);
  }
  Vec3 direction(const Vec2& ab) const { return glm::normalize(p0 + ab.x * e1 + ab.y * e2); }
  // The light's own density (uniform by area) of the direction towards its point x, seen from the origin.
  float own_pdf(const Vec3& x, bool triangle) const {
    const float area = glm::length(glm::cross(e1, e2)) * (triangle ? 0.5f : 1.0f);
    return area_to_solid_angle(1.0f / area, Vec3(0.0f), x, glm::normalize(glm::cross(e1, e2)));
  }
};

// A random view and a light above the shading point at the origin (frame: the identity), near the mirror direction
// for some, off it for others.
struct View {
  float alpha;
  Vec3 wo;
  std::array<LtcLobe, kMaxLtcLobes> lobes;
  int n;
};

View random_view(Pcg32& rng, int i) {
  View s;
  const float alphas[] = {0.08f, 0.15f, 0.25f, 0.32f};
  s.alpha = alphas[i % 4];
  const float theta = 0.1f + 1.2f * rng.next_float(), phi = 2.0f * kPi * rng.next_float();
  s.wo = Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
  s.n = conductor_lobes(s.alpha, s.wo, &s.lobes);
  return s;
}

FlatLight random_light(Pcg32& rng, const Vec3& wo, bool triangle) {
  const Vec3 mirror(-wo.x, -wo.y, wo.z);
  const Vec3 toward = glm::normalize(mirror + 0.5f * (next_vec3(rng) - Vec3(0.5f)));
  const Vec3 c = (1.0f + 2.0f * rng.next_float()) * Vec3(toward.x, toward.y, std::max(toward.z, 0.2f));
  const Frame f(glm::normalize(next_vec3(rng) - Vec3(0.5f)));
  const Vec3 e1 = (0.5f + rng.next_float()) * f.s;
  const Vec3 e2 = (0.5f + rng.next_float()) * glm::normalize(f.t + (rng.next_float() - 0.5f) * f.s);
  return FlatLight(c - 0.5f * (e1 + e2), e1, e2, triangle);
}

TEST(LobeLightSampler, SamplesMatchTheMixtureDensity) {
  Pcg32 rng(71);
  const int kTests = 12;
  int tested = 0;
  for (int i = 0; tested < kTests; ++i) {
    ASSERT_LT(i, 400) << "too few configurations where the lobe takes part";
    const View s = random_view(rng, i);
    const bool triangle = tested % 3 == 2;
    const FlatLight fl = random_light(rng, s.wo, triangle);
    const LobeLightSampler sampler(Frame(), Vec3(0.0f), std::span<const LtcLobe>(s.lobes.data(), size_t(s.n)),
                                   *fl.light);
    if (!sampler.valid()) continue;  // a lobe broader than kMinConcentration at this view, or one that misses
    const LightSampleContext ctx{Vec3(0.0f), Vec3(0.0f, 0.0f, 1.0f)};
    int off = 0, failed = 0;
    Chi2Options o;
    o.seed = 500 + static_cast<uint64_t>(tested);
    o.test_count = kTests;
    o.integration_points = 16;
    o.check_lost_mass = false;  // samples that miss the light by rounding at its edge are dropped (below)
    const Chi2Result r = chi2_test_2d(
        [&](const Vec2& u) -> std::optional<Vec2> {
          const LightSample ls = sampler.sample(ctx, u);
          if (!ls.valid()) {
            ++failed;
            return std::nullopt;
          }
          const Vec2 ab = fl.coordinates(ls.wi);
          const bool on = ab.x > -1e-4f && ab.y > -1e-4f && (triangle ? ab.x + ab.y < 1.0001f : ab.x < 1.0001f && ab.y < 1.0001f);
          off += !on;
          const float expected = sampler.pdf(ls.wi, fl.own_pdf(ls.p, triangle));
          EXPECT_NEAR(ls.pdf, expected, 1e-3f * expected) << "the sample's pdf is the mixture's";
          return glm::clamp(fl.cell(glm::max(ab, Vec2(0.0f)), triangle), Vec2(0.0f), Vec2(kOneMinusEpsilon));
        },
        [&](const Vec2& c) -> double {
          // The triangle's (u, v) map to (a, b) = (u (1 − v), u v), of Jacobian u.
          const Vec2 ab = triangle ? Vec2(c.x * (1.0f - c.y), c.x * c.y) : c;
          const Vec3 w = fl.direction(ab);
          const Vec3 x = fl.p0 + ab.x * fl.e1 + ab.y * fl.e2;
          return fl.per_ab(ab, sampler.pdf(w, fl.own_pdf(x, triangle))) * (triangle ? c.x : 1.0f);
        },
        Chi2Grid2D{}, o);
    const std::string what = fmt::format("{} {}, α {}, q {:.3f}", triangle ? "triangle" : "quad", tested, s.alpha,
                                         sampler.fraction());
    EXPECT_TRUE(r.passed) << what << ": " << r.message;
    EXPECT_NEAR(r.pdf_integral, 1.0, 3e-3) << what;
    EXPECT_EQ(off, 0) << what << ": samples off the light";
    EXPECT_LT(failed, 20) << what << ": samples lost at the light's edge";
    ++tested;
  }
}

Vec3 view_at(float theta_deg) {
  const float t = theta_deg * kPi / 180.0f;
  return Vec3(std::sin(t), 0.0f, std::cos(t));
}

// A 1 × 1 quad light at distance d along the unit direction c, facing the origin (its normal e1 × e2 = t × s = −c).
FlatLight facing_quad(const Vec3& c, float d, bool two_sided = true) {
  const Frame f(c);
  return FlatLight(d * c - 0.5f * (f.s + f.t), f.t, f.s, false, two_sided);
}

TEST(LobeLightSampler, TakesPartOnlyWhereANarrowLobeSeesTheLight) {
  const Vec3 wo = view_at(40.0f);
  const Vec3 mirror(-wo.x, -wo.y, wo.z);
  std::array<LtcLobe, kMaxLtcLobes> lobes;
  const int n = conductor_lobes(0.1f, wo, &lobes);
  const std::span<const LtcLobe> glossy(lobes.data(), size_t(n));
  const FlatLight above = facing_quad(mirror, 2.0f);
  const LobeLightSampler s(Frame(), Vec3(0.0f), glossy, *above.light);
  ASSERT_TRUE(s.valid());
  EXPECT_GE(s.fraction(), 0.5f) << "the light sits in the highlight";
  EXPECT_LE(s.fraction(), LobeLightSampler::kMaxFraction);
  // A Lambertian lobe: the light's own sampling already follows it.
  const std::array<LtcLobe, 1> lambert = {LtcLobe{Ltc(), Rgb(0.8f)}};
  EXPECT_FALSE(LobeLightSampler(Frame(), Vec3(0.0f), lambert, *above.light).valid());
  // No lobes at all (a BSDF without an LTC fit).
  EXPECT_FALSE(LobeLightSampler(Frame(), Vec3(0.0f), {}, *above.light).valid());
  // A one-sided light that turns its back on the point (its normal s × t = +c).
  const Frame f(mirror);
  const FlatLight back(2.0f * mirror - 0.5f * (f.s + f.t), f.s, f.t, false, false);
  EXPECT_FALSE(LobeLightSampler(Frame(), Vec3(0.0f), glossy, *back.light).valid());
  const FlatLight front = facing_quad(mirror, 2.0f, false);
  EXPECT_TRUE(LobeLightSampler(Frame(), Vec3(0.0f), glossy, *front.light).valid()) << "the same light facing it";
  // Below the surface, where the lobe is 0.
  const FlatLight below = facing_quad(glm::normalize(Vec3(0.3f, 0.2f, -1.0f)), 2.0f);
  EXPECT_FALSE(LobeLightSampler(Frame(), Vec3(0.0f), glossy, *below.light).valid());
}

// The direct light of a 1 × 1 quad in the highlight of a GGX α 0.1 conductor, ∫_P f cos L dω, by sampling the light
// by area and by the mixture: the same mean within the noise, and the mixture's variance lower, by more than 5× with
// the light in the highlight (7.6× measured: the fifth of the samples left to area sampling bounds it), and lower
// with the light in the lobe's tail (8.4× measured).
TEST(LobeLightSampler, LowersTheVarianceOfAHighlight) {
  const ConductorFresnel f1;
  const float alpha = 0.1f;
  const MicrofacetDistribution d(MicrofacetType::GGX, alpha, alpha);
  const ConductorCompensation comp = ConductorCompensation::make(MicrofacetType::GGX, alpha, f1, true);
  const RoughConductorBsdf bsdf(d, &f1, &comp);
  const Vec3 wo = view_at(40.0f);
  std::array<LtcLobe, kMaxLtcLobes> lobes;
  const int n = bsdf.ltc_lobes(wo, Vec3(0.0f, 0.0f, 1.0f), lobes.data());
  const Vec3 mirror(-wo.x, -wo.y, wo.z);
  const LightSampleContext ctx{Vec3(0.0f), Vec3(0.0f, 0.0f, 1.0f)};
  for (const float offset : {0.0f, 0.5f}) {
    const Vec3 c = glm::normalize(mirror + Vec3(0.0f, offset, 0.0f));
    const FlatLight light = facing_quad(c, 2.0f);
    const LobeLightSampler shaped(Frame(), Vec3(0.0f), std::span<const LtcLobe>(lobes.data(), size_t(n)),
                                  *light.light);
    ASSERT_TRUE(shaped.valid()) << "offset " << offset;
    const int kSamples = 1 << 16;
    double sum[2] = {0, 0}, sum2[2] = {0, 0};
    Pcg32 rng(3);
    for (int i = 0; i < kSamples; ++i) {
      const Vec2 u(rng.next_float(), rng.next_float());
      for (int m = 0; m < 2; ++m) {
        const LightSample ls = m == 0 ? light.light->sample(ctx, u) : shaped.sample(ctx, u);
        const double x = ls.valid() ? double(bsdf.eval(wo, ls.wi, TransportMode::Radiance).g) / ls.pdf : 0.0;
        sum[m] += x;
        sum2[m] += x * x;
      }
    }
    double mean[2], var[2];
    for (int m = 0; m < 2; ++m) {
      mean[m] = sum[m] / kSamples;
      var[m] = sum2[m] / kSamples - mean[m] * mean[m];
    }
    const double se = std::sqrt((var[0] + var[1]) / kSamples);
    std::printf("offset %.1f: q %.3f, mean %.5f (area) %.5f (lobe), variance %.3e (area) %.3e (lobe), %.1fx\n",
                offset, shaped.fraction(), mean[0], mean[1], var[0], var[1], var[0] / var[1]);
    EXPECT_NEAR(mean[0], mean[1], 5.0 * se) << "offset " << offset;
    EXPECT_GT(var[0], (offset == 0.0f ? 5.0 : 1.0) * var[1]) << "offset " << offset;
  }
}

}  // namespace
}  // namespace kozu::test
