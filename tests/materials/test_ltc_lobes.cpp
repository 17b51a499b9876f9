// Bsdf::ltc_lobes (the BSDFs' LTC approximations that "direct": "ltc" integrates in closed form, docs/lights.md):
// which materials have them, that their energy Σ w_k matches the BSDF's directional albedo, how close their shape
// is (relative L1 distance), and that the fitted compensated lobe approximates kozu's compensated conductor
// better than the single-scattering fit plus a clamped cosine.
#include "materials/bsdf.h"
#include "materials/conductor.h"
#include "materials/ltc_table.h"
#include "materials/microfacet.h"
#include "support/bsdf_test.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

namespace kozu::test {
namespace {

Vec3 view(float theta_deg) {
  const float t = theta_deg * kPi / 180.0f;
  return Vec3(std::sin(t), 0.0f, std::cos(t));
}

// ∫ |f cos − f̃| dω / ∫ f cos dω over the upper hemisphere, green channel: midpoint rule in (cos θ, φ), 256 × 512
// cells of equal solid angle.
double relative_l1(const Bsdf& bsdf, const Vec3& wo, std::span<const LtcLobe> lobes) {
  const int nt = 256, np = 512;
  double diff = 0.0, total = 0.0;
  for (int i = 0; i < nt; ++i)
    for (int j = 0; j < np; ++j) {
      const double z = (i + 0.5) / nt, phi = 2.0 * kPi * (j + 0.5) / np, r = std::sqrt(1.0 - z * z);
      const Vec3 wi(static_cast<float>(r * std::cos(phi)), static_cast<float>(r * std::sin(phi)),
                    static_cast<float>(z));
      const double f = bsdf.eval(wo, wi, TransportMode::Radiance).g;
      double g = 0.0;
      for (const LtcLobe& l : lobes) g += double(l.weight.g) * l.ltc.eval(wi);
      diff += std::abs(f - g);
      total += f;
    }
  return total > 0.0 ? diff / total : 0.0;
}

struct Case {
  std::string name, json;
  double energy_tolerance;  // relative, beyond 4 standard errors of the albedo estimate
};

// Energy: Σ w_k against the albedo by sampling (bsdf_test.h). The weights are the materials' own albedo tables
// (32 μ nodes, linear: ~2e-3), so 1 % bounds them; a measured metal's single scattering uses Schlick's form from
// F(1) in place of its Fresnel curve, within 4 % for gold (the worst error is printed).
const std::vector<Case>& cases() {
  static const std::vector<Case> c = {
      {"lambert", R"("type": "diffuse", "albedo": [0.8, 0.5, 0.2])", 1e-4},
      {"conductor_f1", R"("type": "conductor", "roughness": 0.3, "multiscatter": "compensated")", 0.01},
      {"conductor_f1_beckmann",
       R"("type": "conductor", "roughness": 0.5, "distribution": "beckmann", "multiscatter": "compensated")", 0.01},
      {"gold_compensated", R"("type": "conductor", "metal": "Au", "roughness": 0.4, "multiscatter": "compensated")",
       0.04},
      {"gold_single", R"("type": "conductor", "metal": "Au", "roughness": 0.2)", 0.04},
      {"plastic", R"("type": "plastic", "albedo": [0.7, 0.4, 0.2], "roughness": 0.3)", 0.01},
      {"plastic_ior_2", R"("type": "plastic", "albedo": 0.5, "roughness": 0.6, "ior": 2.0)", 0.01},
      {"plastic_smooth", R"("type": "plastic", "albedo": [0.7, 0.4, 0.2])", 0.01},
      {"standard_dielectric", R"("type": "standard", "base_color": [0.5, 0.3, 0.2], "roughness": 0.5)", 0.01},
      {"standard_metal", R"("type": "standard", "metallic": 1, "base_color": [0.9, 0.6, 0.3], "roughness": 0.5)", 0.01},
      {"standard_half_metal", R"("type": "standard", "metallic": 0.5, "base_color": 0.8, "roughness": 0.3)", 0.01},
  };
  return c;
}

TEST(LtcLobes, EnergyMatchesTheAlbedo) {
  for (const Case& c : cases()) {
    double worst = 0.0;
    const auto material = material_from_json(c.json);
    Arena arena;
    const Bsdf* bsdf = material->bsdf(hit_at_uv(0.5f, 0.5f), arena);
    for (const float theta : {0.0f, 30.0f, 60.0f, 80.0f}) {
      const Vec3 wo = view(theta);
      std::array<LtcLobe, kMaxLtcLobes> lobes;
      const int n = bsdf->ltc_lobes(wo, Vec3(0, 0, 1), lobes.data());
      ASSERT_GT(n, 0) << c.name;
      Rgb w(0.0f);
      for (int k = 0; k < n; ++k) w += lobes[k].weight;
      const std::optional<Rgb> ltc_albedo = bsdf->ltc_albedo(wo);  // the same sum, as the path's albedo feature takes it
      ASSERT_TRUE(ltc_albedo) << c.name;
      for (int ch = 0; ch < 3; ++ch) EXPECT_FLOAT_EQ((*ltc_albedo)[ch], w[ch]) << c.name << " θ " << theta;
      const AlbedoEstimate a = directional_albedo(*bsdf, wo, TransportMode::Radiance, 17);
      const double l1 = relative_l1(*bsdf, wo, std::span<const LtcLobe>(lobes.data(), size_t(n)));
      std::printf("%-22s θ %2.0f°: %d lobes, Σw %.4f, albedo %.4f ± %.4f (green), relative L1 %.3f\n", c.name.c_str(),
                  theta, n, w.g, a.mean.g, a.se.g, l1);
      for (int ch = 0; ch < 3; ++ch) {
        EXPECT_NEAR(w[ch], a.mean[ch], 4.0 * a.se[ch] + c.energy_tolerance * a.mean[ch])
            << c.name << " θ " << theta << " channel " << ch;
        worst = std::max(worst, std::abs(double(w[ch]) / a.mean[ch] - 1.0));
      }
    }
    std::printf("%s: worst relative energy error %.4f\n", c.name.c_str(), worst);
  }
}

// Transmissive and Dirac-only BSDFs have none (direct lighting samples them as "sample" does).
TEST(LtcLobes, NoneForTransmissionOrDiracs) {
  for (const char* json : {R"("type": "dielectric", "roughness": 0.3)", R"("type": "conductor")",
                           R"("type": "standard", "transmission": 1, "roughness": 0.4)"}) {
    const auto material = material_from_json(json);
    Arena arena;
    const Bsdf* bsdf = material->bsdf(hit_at_uv(0.5f, 0.5f), arena);
    std::array<LtcLobe, kMaxLtcLobes> lobes;
    EXPECT_EQ(bsdf->ltc_lobes(view(30.0f), Vec3(0, 0, 1), lobes.data()), 0) << json;
  }
}

// The diffuse models that are not Lambertian: a clamped cosine that equals f cos towards the light.
TEST(LtcLobes, DiffuseModelsMatchTowardsTheLight) {
  for (const char* json : {R"("type": "diffuse", "model": "cod-multiscatter", "albedo": 0.7, "gloss": 0.3)",
                           R"("type": "diffuse", "model": "shirley", "albedo": 0.7)",
                           R"("type": "standard", "diffuse_model": "cod-multiscatter", "roughness": 0.8)"}) {
    const auto material = material_from_json(json);
    Arena arena;
    const Bsdf* bsdf = material->bsdf(hit_at_uv(0.5f, 0.5f), arena);
    for (const Vec3& toward : {Vec3(0, 0, 1), glm::normalize(Vec3(-0.6f, 0.3f, 0.5f))}) {
      std::array<LtcLobe, kMaxLtcLobes> lobes;
      const Vec3 wo = view(40.0f);
      const int n = bsdf->ltc_lobes(wo, toward, lobes.data());
      ASSERT_GT(n, 0) << json;
      const LtcLobe& base = lobes[size_t(n - 1)];  // the diffuse lobe comes last
      const float expected = bsdf->eval(wo, toward, TransportMode::Radiance).g;
      if (n == 1) {
        EXPECT_NEAR(base.weight.g * base.ltc.eval(toward), expected, 1e-5f * expected) << json;
      } else {  // standard: the diffuse lobe is what f has besides the specular lobe's microfacet term
        EXPECT_GT(base.weight.g * base.ltc.eval(toward), 0.5f * expected) << json;
      }
    }
  }
}

// kozu's compensated conductor (F = 1) takes, from kLtcCompensatedMinAlpha up, one lobe of the compensated
// table, and below it the single-scattering lobe plus the coupled lobe as a clamped cosine: at every roughness
// the choice is the one closer to the BSDF (relative L1 summed over four views). Beckmann's fits are poor below
// α ≈ 0.5 either way (docs/lights.md), and there the two differ by at most 5 %: only the rough side is asserted.
TEST(LtcLobes, CompensatedConductorTakesTheCloserApproximation) {
  const ConductorFresnel f1;
  for (const MicrofacetType type : {MicrofacetType::GGX, MicrofacetType::Beckmann})
    for (const float alpha : {0.1f, 0.2f, 0.3f, 0.45f, 0.55f, 0.65f, 0.8f, 1.0f}) {
      const MicrofacetDistribution d(type, alpha, alpha);
      const ConductorCompensation comp = ConductorCompensation::make(type, alpha, f1, true);
      const RoughConductorBsdf bsdf(d, &f1, &comp);
      const bool ggx = type == MicrofacetType::GGX;
      const bool one = alpha >= kLtcCompensatedMinAlpha;
      double chosen = 0.0, other = 0.0;
      for (const float theta : {0.0f, 30.0f, 60.0f, 75.0f}) {
        const Vec3 wo = view(theta);
        std::array<LtcLobe, kMaxLtcLobes> lobes;
        const int n = bsdf.ltc_lobes(wo, Vec3(0, 0, 1), lobes.data());
        ASSERT_EQ(n, one ? 1 : 2);
        std::array<LtcLobe, 2> alternative;
        if (one) {
          const LtcLobeFit ss = ltc_lobe(ggx ? LtcBrdf::Ggx : LtcBrdf::Beckmann, wo, alpha);
          alternative = {LtcLobe{ss.ltc, Rgb(ss.norm)}, LtcLobe{Ltc(), Rgb(1.0f - comp.e.eval(wo.z))}};
        } else {
          const LtcLobeFit c = ltc_lobe(ggx ? LtcBrdf::GgxCompensated : LtcBrdf::BeckmannCompensated, wo, alpha);
          alternative = {LtcLobe{c.ltc, lobes[0].weight + lobes[1].weight}, LtcLobe{Ltc(), Rgb(0.0f)}};
        }
        chosen += relative_l1(bsdf, wo, std::span<const LtcLobe>(lobes.data(), size_t(n)));
        other += relative_l1(bsdf, wo, alternative);
      }
      std::printf("%s α %.2f: relative L1 over four views, %s %.3f, the other %.3f\n", ggx ? "ggx" : "beckmann", alpha,
                  one ? "one compensated lobe" : "two lobes", chosen, other);
      if (ggx || one) {
        EXPECT_LT(chosen, other) << (ggx ? "ggx" : "beckmann") << " α " << alpha;
      }
    }
}

// Bsdf::narrowest_ltc_alpha, the cheap test before ltc_lobes (integrators/lobe_light_sampler.h): the α of the
// narrowest fitted lobe (roughness² for the roughness key; the geometric mean of an anisotropic pair), 1 for models
// with clamped cosines alone, a smooth coat (a Dirac lobe) or transmission (no lobes).
TEST(LtcLobes, NarrowestAlphaIsTheSmoothestFittedLobe) {
  const std::vector<std::pair<std::string, float>> cases = {
      {R"("type": "diffuse", "albedo": 0.5)", 1.0f},
      {R"("type": "conductor", "roughness": 0.3)", 0.09f},
      {R"("type": "conductor", "alpha_u": 0.04, "alpha_v": 0.16)", 0.08f},
      {R"("type": "plastic", "albedo": 0.5, "roughness": 0.2)", 0.04f},
      {R"("type": "plastic", "albedo": 0.5, "roughness": 0)", 1.0f},
      {R"("type": "standard", "base_color": 0.5, "roughness": 0.5)", 0.25f},
      {R"("type": "standard", "base_color": 0.5, "roughness": 0.5, "clearcoat": 1, "clearcoat_roughness": 0.2)", 0.04f},
      {R"("type": "standard", "base_color": 0.5, "roughness": 0.5, "transmission": 1)", 1.0f},
  };
  for (const auto& [json, alpha] : cases) {
    const auto material = material_from_json(json);
    Arena arena;
    const Bsdf* bsdf = material->bsdf(hit_at_uv(0.5f, 0.5f), arena);
    EXPECT_NEAR(bsdf->narrowest_ltc_alpha(), alpha, 2e-3f) << json;
    std::array<LtcLobe, kMaxLtcLobes> lobes;
    const int n = bsdf->ltc_lobes(view(30.0f), Vec3(0, 0, 1), lobes.data());
    bool fitted = false;  // a lobe that is not the clamped cosine
    for (int k = 0; k < n; ++k) fitted |= lobes[k].ltc.det_inv() != 1.0f;
    EXPECT_EQ(fitted, alpha < 1.0f) << json;
  }
}

}  // namespace
}  // namespace kozu::test
