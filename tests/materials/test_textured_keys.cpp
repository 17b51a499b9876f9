// Textured keys of conductor, dielectric, plastic and subsurface (materials/roughness.h,
// materials/roughness_tables.h):
//   1. a key given as a checker of two values a and b gives, at hits in an a-square and a b-square, the BSDF
//      (eval, pdf, sample with fixed random numbers) of the same material with the plain value a, resp. b; and the
//      subsurface material's profile and exit BSDF likewise. Exactly (bit for bit): the roughness values are
//      chosen on the 1/255 steps varying roughness is rounded to, so the textured path feeds the same floats
//      through the same arithmetic (roughness_distribution repeats read_roughness's; the tables of a level are
//      built with the plain value's expressions; a textured eta/k's F_avg and F_ms per hit use the functions the
//      constant's precomputation uses). Colours are not rounded; a constant texture is not rounded at all.
//   2. RoughnessTables: each level built once under concurrent lookups; a constant never rounded;
//   3. parsing: textured keys accepted, bad textures rejected with the JSON path.
#include "support/bsdf_test.h"

#include "bssrdf/probe_sampling.h"
#include "core/arena.h"
#include "core/error.h"
#include "core/json_reader.h"
#include "core/rng.h"
#include "materials/material.h"
#include "materials/roughness_tables.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace kozu::test {
namespace {

// The checker below has 2 × 2 squares: a at (0.25, 0.25), b at (0.75, 0.25) (checker_texture.h).
const Vec2 kSquareA(0.25f, 0.25f), kSquareB(0.75f, 0.25f);

struct Slot {
  std::string a, b;  // JSON values
};

struct Case {
  std::string name;
  std::string body;         // the material's JSON with $0, $1 where the slots' values go
  std::vector<Slot> slots;  // one per textured key
};

std::string fill(std::string body, const std::vector<Slot>& slots, int which) {
  for (size_t i = 0; i < slots.size(); ++i) {
    const std::string mark = fmt::format("${}", i);
    const std::string value = which == 0   ? slots[i].a
                              : which == 1 ? slots[i].b
                                           : fmt::format(R"({{"type": "checker", "scale": [2, 2], "a": {}, "b": {}}})",
                                                         slots[i].a, slots[i].b);
    const size_t at = body.find(mark);
    body = body.substr(0, at) + value + body.substr(at + mark.size());
  }
  return body;
}

std::vector<Case> cases() {
  // Roughness values on the 1/255 steps (51/255 = 0.2, 153/255 = 0.6, ...).
  const Slot r{"0.2", "0.6"};
  std::vector<Case> c;
  for (const char* ms : {"none", "compensated", "stochastic"}) {
    const std::string m = fmt::format(R"("multiscatter": "{}")", ms);
    c.push_back({fmt::format("conductor_roughness_{}", ms),
                 R"("type": "conductor", "metal": "Au", "roughness": $0, )" + m,
                 {r}});
    c.push_back({fmt::format("dielectric_roughness_{}", ms),
                 R"("type": "dielectric", "ior": 1.5, "roughness": $0, )" + m,
                 {r}});
  }
  c.push_back({"conductor_white_alpha_compensated",
               R"("type": "conductor", "alpha": $0, "multiscatter": "compensated")",
               {{"0.4", "0.8"}}});
  c.push_back({"conductor_gloss_compensated",
               R"("type": "conductor", "metal": "Cu", "gloss": $0, "gloss_model": "aw", "multiscatter": "compensated")",
               {{"0.2", "0.6"}}});
  c.push_back(
      {"conductor_beckmann_compensated",
       R"("type": "conductor", "eta": [0.2, 0.9, 1.1], "k": [3, 2.5, 2], "roughness": $0, "distribution": "beckmann", "multiscatter": "compensated", "ms_fresnel": "average")",
       {r}});
  // alpha_u/alpha_v: exact without compensation (its tables are keyed on the rounded RMS α, see roughness.h).
  c.push_back({"conductor_anisotropic_none",
               R"("type": "conductor", "metal": "Ag", "alpha_u": $0, "alpha_v": $1)",
               {{"0.2", "0.6"}, {"0.4", "0.8"}}});
  c.push_back({"dielectric_anisotropic_none",
               R"("type": "dielectric", "ior": 1.33, "alpha_u": $0, "alpha_v": 0.4321)",
               {{"0.2", "0.6"}}});
  c.push_back({"dielectric_from_inside_ior",
               R"("type": "dielectric", "ior": 0.7, "alpha": $0, "multiscatter": "compensated")",
               {{"0.2", "0.6"}}});
  c.push_back(
      {"plastic_roughness", R"("type": "plastic", "albedo": [0.8, 0.4, 0.2], "ior": 1.6, "roughness": $0)", {r}});
  c.push_back({"plastic_gloss", R"("type": "plastic", "gloss": $0)", {{"0.4", "0.8"}}});
  // Colour keys (any values: colours are not rounded).
  const Slot albedo{"[0.8, 0.4, 0.2]", "[0.1, 0.5, 0.9]"};
  c.push_back({"plastic_albedo", R"("type": "plastic", "albedo": $0)", {albedo}});
  c.push_back({"plastic_albedo_smooth", R"("type": "plastic", "albedo": $0, "roughness": 0, "ior": 1.7)", {albedo}});
  c.push_back(
      {"plastic_albedo_and_roughness", R"("type": "plastic", "albedo": $0, "alpha": $1)", {albedo, {"0.2", "0.6"}}});
  const Slot eta{"[0.2, 0.9, 1.1]", "[1.5, 0.6, 0.3]"}, k{"[3, 2.5, 2]", "[1, 4, 0]"};
  for (const char* ms : {"none", "compensated", "stochastic"})
    c.push_back({fmt::format("conductor_eta_k_{}", ms),
                 fmt::format(R"("type": "conductor", "eta": $0, "k": $1, "roughness": 0.5, "multiscatter": "{}")", ms),
                 {eta, k}});
  c.push_back({"conductor_eta_smooth", R"("type": "conductor", "eta": $0, "k": [3, 2.5, 2])", {eta}});
  c.push_back(
      {"conductor_k_average_approximate",
       R"("type": "conductor", "eta": [0.2, 0.9, 1.1], "k": $0, "roughness": 0.4, "multiscatter": "compensated", "ms_fresnel": "average", "fresnel": "approximate")",
       {k}});
  c.push_back({"conductor_eta_k_roughness_compensated",
               R"("type": "conductor", "eta": $0, "k": $1, "roughness": $2, "multiscatter": "compensated")",
               {eta, k, r}});
  c.push_back({"subsurface_albedo_mfp",
               R"("type": "subsurface", "albedo": $0, "mfp": $1)",
               {albedo, {"[1, 0.5, 0.25]", "[0.1, 2, 0.7]"}}});
  c.push_back({"subsurface_dmfp_rough",
               R"("type": "subsurface", "dmfp": $0, "roughness": 0.4)",
               {{"[1, 0.5, 0.25]", "[0.1, 2, 0.7]"}}});
  c.push_back({"subsurface_albedo_diffuse_ior",
               R"("type": "subsurface", "albedo": $0, "mfp": 0.3, "parameterization": "diffuse", "ior": 1.2)",
               {albedo}});
  // The CoD multiple-scattering diffuse's gloss, given as gloss or through α.
  c.push_back({"diffuse_cod_gloss", R"("type": "diffuse", "model": "cod-multiscatter", "gloss": $0)", {r}});
  c.push_back({"diffuse_cod_roughness_albedo",
               R"("type": "diffuse", "model": "cod-multiscatter", "albedo": $0, "roughness": $1)",
               {albedo, r}});
  c.push_back({"diffuse_shirley_f0_albedo",
               R"("type": "diffuse", "model": "shirley", "albedo": $0, "f0": $1)",
               {albedo, {"0.04", "0.3"}}});
  c.push_back({"diffuse_cod_gloss_aw",
               R"("type": "diffuse", "model": "cod-multiscatter", "gloss": $0, "gloss_model": "aw")",
               {r}});
  c.push_back({"subsurface_roughness", R"("type": "subsurface", "mfp": [1, 0.5, 0.25], "roughness": $0)", {r}});
  return c;
}

// Directions on both sides (local frame).
std::vector<Vec3> directions() {
  std::vector<Vec3> d;
  for (const double theta : {10.0, 40.0, 75.0, 120.0, 160.0})
    for (const double phi : {0.0, 130.0, 250.0}) d.push_back(direction_from_angles(theta, phi));
  return d;
}

// Exact equality of everything a BSDF reports.
void expect_same_bsdf(const Bsdf& a, const Bsdf& b, const std::string& where) {
  ASSERT_EQ(a.flags(), b.flags()) << where;
  const std::vector<Vec3> dirs = directions();
  for (const Vec3& wo : dirs) {
    for (const Vec3& wi : dirs) {
      for (const TransportMode mode : {TransportMode::Radiance, TransportMode::Importance}) {
        const Rgb fa = a.eval(wo, wi, mode), fb = b.eval(wo, wi, mode);
        EXPECT_EQ(fa.r, fb.r) << where;
        EXPECT_EQ(fa.g, fb.g) << where;
        EXPECT_EQ(fa.b, fb.b) << where;
      }
      EXPECT_EQ(a.pdf(wo, wi), b.pdf(wo, wi)) << where;
    }
    for (const float u_lobe : {0.05f, 0.3f, 0.6f, 0.97f}) {
      for (const Vec2 u : {Vec2(0.1f, 0.2f), Vec2(0.5f, 0.9f), Vec2(0.8f, 0.4f)}) {
        const BsdfSample sa = a.sample(wo, u_lobe, u, TransportMode::Radiance);
        const BsdfSample sb = b.sample(wo, u_lobe, u, TransportMode::Radiance);
        EXPECT_EQ(sa.valid(), sb.valid()) << where;
        if (!sa.valid() || !sb.valid()) continue;
        EXPECT_EQ(sa.wi, sb.wi) << where;
        EXPECT_EQ(sa.f, sb.f) << where;
        EXPECT_EQ(sa.pdf, sb.pdf) << where;
        EXPECT_EQ(sa.flags, sb.flags) << where;
        EXPECT_EQ(sa.eta, sb.eta) << where;
      }
    }
  }
}

void expect_same_profile(const RgbProfile& a, const RgbProfile& b, const std::string& where) {
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(a.r_max(c), b.r_max(c)) << where << " channel " << c;
    for (const float r : {0.001f, 0.05f, 0.3f, 2.0f}) EXPECT_EQ(a.pdf_radius(c, r), b.pdf_radius(c, r)) << where;
    for (const float u : {0.1f, 0.5f, 0.9f}) EXPECT_EQ(a.sample_radius(c, u), b.sample_radius(c, u)) << where;
  }
  for (const float r : {0.001f, 0.05f, 0.3f, 2.0f}) EXPECT_EQ(a.eval(r), b.eval(r)) << where;
}

// The textured material at the hit `square` against the plain material with that square's values.
void expect_same_material(const Material& textured, const Material& plain, const Vec2& square,
                          const std::string& where) {
  Arena arena;
  const SurfaceInteraction si = hit_at_uv(square.x, square.y);
  expect_same_bsdf(*textured.bsdf(si, arena), *plain.bsdf(hit_at_uv(0.5f, 0.5f), arena), where);
  ASSERT_EQ(textured.has_subsurface(), plain.has_subsurface()) << where;
  if (!textured.has_subsurface()) return;
  expect_same_profile(*textured.subsurface_profile(si, arena), *plain.subsurface_profile(hit_at_uv(0.5f, 0.5f), arena),
                      where + " profile");
  expect_same_bsdf(*textured.subsurface_exit_bsdf(si, arena), *plain.subsurface_exit_bsdf(hit_at_uv(0.5f, 0.5f), arena),
                   where + " exit");
}

class TexturedKey : public ::testing::TestWithParam<Case> {};

TEST_P(TexturedKey, CheckerSquaresEqualPlainValues) {
  const Case& c = GetParam();
  const auto textured = material_from_json(fill(c.body, c.slots, 2));
  const auto plain_a = material_from_json(fill(c.body, c.slots, 0));
  const auto plain_b = material_from_json(fill(c.body, c.slots, 1));
  expect_same_material(*textured, *plain_a, kSquareA, c.name + " a-square");
  expect_same_material(*textured, *plain_b, kSquareB, c.name + " b-square");
  // The squares differ (the test could fail): the two plain materials are not the same BSDF, or profile.
  Arena arena;
  const SurfaceInteraction si = hit_at_uv(0.5f, 0.5f);
  const Vec3 wo = direction_from_angles(40.0, 0.0), wi = direction_from_angles(30.0, 180.0);
  const Bsdf& ba = *plain_a->bsdf(si, arena);
  const Bsdf& bb = *plain_b->bsdf(si, arena);
  bool differ = ba.eval(wo, wi, TransportMode::Radiance) != bb.eval(wo, wi, TransportMode::Radiance);
  const BsdfSample sa = ba.sample(wo, 0.5f, Vec2(0.3f, 0.6f), TransportMode::Radiance);
  const BsdfSample sb = bb.sample(wo, 0.5f, Vec2(0.3f, 0.6f), TransportMode::Radiance);
  differ = differ || sa.f != sb.f;  // the smooth ones differ in their Dirac samples only
  if (plain_a->has_subsurface())
    differ = differ ||
             plain_a->subsurface_profile(si, arena)->eval(0.1f) != plain_b->subsurface_profile(si, arena)->eval(0.1f);
  EXPECT_TRUE(differ) << c.name;
}

// A constant texture is the plain value exactly, even off the 1/255 steps (it is not rounded).
TEST_P(TexturedKey, ConstantTextureEqualsPlainValue) {
  const Case& c = GetParam();
  std::vector<Slot> odd = c.slots;
  for (Slot& s : odd) s.a = "0.3337";
  std::string body = c.body;
  for (size_t i = 0; i < odd.size(); ++i) {
    const std::string mark = fmt::format("${}", i);
    const size_t at = body.find(mark);
    body = body.substr(0, at) + R"({"type": "constant", "value": 0.3337})" + body.substr(at + mark.size());
  }
  expect_same_material(*material_from_json(body), *material_from_json(fill(c.body, odd, 0)), kSquareB,
                       c.name + " constant");
}

INSTANTIATE_TEST_SUITE_P(Materials, TexturedKey, ::testing::ValuesIn(cases()),
                         [](const auto& p) { return p.param.name; });

// ---- the table cache ---------------------------------------------------------------------------------------

// Levels are built once each, whatever the number of threads asking, and every caller gets its level's tables.
TEST(RoughnessTables, EachLevelBuiltOnceUnderConcurrency) {
  std::atomic<int> builds{0};
  const RoughnessTables<float> tables(std::nullopt, [&](float key) {
    builds.fetch_add(1);
    std::this_thread::sleep_for(std::chrono::microseconds(200));  // widen the race window
    return key;
  });
  std::vector<std::thread> threads;
  std::atomic<int> wrong{0};
  for (int t = 0; t < 8; ++t)
    threads.emplace_back([&, t] {
      for (int i = 0; i < 2000; ++i) {
        const int level = (i * 7 + t * 13) % 64;
        const float x = level / 255.0f + 0.001f;  // rounds to `level`
        if (tables.at(x) != level / 255.0f) wrong.fetch_add(1);
      }
    });
  for (std::thread& th : threads) th.join();
  EXPECT_EQ(builds.load(), 64);
  EXPECT_EQ(wrong.load(), 0);
  // A constant is built at once, exactly, and never rounded.
  const RoughnessTables<float> constant(0.3337f, [](float key) { return key; });
  EXPECT_EQ(constant.at(0.9f), 0.3337f);
}

// ---- parsing -----------------------------------------------------------------------------------------------

std::string error_of(const std::string& body) {
  try {
    material_from_json(body);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(TexturedKeyParse, Errors) {
  EXPECT_EQ(error_of(R"("type": "conductor", "roughness": {"type": "constant", "value": 2})"),
            "test.json: /materials/m/roughness/value: expected a number in [0, 1], got 2");
  EXPECT_EQ(error_of(R"("type": "plastic", "alpha": {"type": "checker", "a": 0.1, "b": -0.5})"),
            "test.json: /materials/m/alpha/b: expected a number in [0, 1], got -0.5");
  EXPECT_EQ(error_of(R"("type": "dielectric", "roughness": {"type": "constant", "value": 0.3}, "gloss": 0.5)"),
            "test.json: /materials/m/gloss: give only one of 'roughness', 'alpha', 'alpha_u'/'alpha_v' or 'gloss' "
            "(also got 'roughness')");
  EXPECT_EQ(error_of(R"("type": "subsurface", "mfp": 1, "alpha_u": {"type": "constant", "value": 0.3})"),
            "test.json: /materials/m/alpha_u: give both 'alpha_u' and 'alpha_v'");
  EXPECT_EQ(error_of(R"("type": "conductor", "gloss": {"type": "constant", "value": 0.3, "scale": 2})"),
            "test.json: /materials/m/gloss/scale: unknown key 'scale'");
  EXPECT_EQ(error_of(R"("type": "dielectric", "ior": 1, "roughness": {"type": "constant", "value": 0.3},
                        "multiscatter": "stochastic")"),
            "test.json: /materials/m/multiscatter: \"stochastic\" needs an ior different from 1 (an index-matched "
            "interface does not scatter)");
  // Image textures need the scene's texture cache (none here): refused by name.
  EXPECT_EQ(error_of(R"("type": "plastic", "roughness": {"type": "image", "file": "r.png"})"),
            "test.json: /materials/m/roughness: image textures are not available here");
}

TEST(TexturedKeyParse, TexturedRoughnessIsRough) {
  // A textured roughness makes a rough surface even where it is 0 (α clamped to 1e-3, roughness.h), while the
  // plain value 0 makes the smooth (Dirac) one.
  for (const char* type : {"conductor", "dielectric", "plastic"}) {
    const auto textured =
        material_from_json(fmt::format(R"("type": "{}", "roughness": {{"type": "checker", "a": 0, "b": 0.5}})", type));
    const auto plain = material_from_json(fmt::format(R"("type": "{}", "roughness": 0)", type));
    Arena arena;
    const SurfaceInteraction si = hit_at_uv(kSquareA.x, kSquareA.y);
    EXPECT_FALSE(textured->bsdf(si, arena)->flags() & kBsdfSpecular) << type;
    EXPECT_TRUE(plain->bsdf(si, arena)->flags() & kBsdfSpecular) << type;
  }
}

// Material::may_be_specular: where a material says it never makes a specular (Dirac) lobe, no BSDF it makes at any
// point samples one, over a checker of roughness values, grazing and normal views and both sides; and the smooth
// ones say they may, and do (so the check sees a specular sample where there is one). The visible emission's paths
// end at the first kind (integrators/path.cpp), which is exact only if this holds.
TEST(MaterialSpecular, SaysWhetherItsBsdfsCanHaveADiracLobe) {
  const std::string rough = R"({"type": "checker", "scale": [2, 2], "a": 0.002, "b": 0.4})";
  const struct {
    std::string body;
    bool specular;
  } cases[] = {
      {R"("type": "diffuse", "albedo": 0.5)", false},
      {R"("type": "diffuse", "model": "cod-multiscatter", "albedo": 0.5, "gloss": 0.9)", false},
      {R"("type": "conductor", "roughness": 0.2)", false},
      {fmt::format(R"("type": "conductor", "roughness": {})", rough), false},
      {R"("type": "conductor")", true},
      {R"("type": "dielectric", "roughness": 0.12)", false},
      {fmt::format(R"("type": "dielectric", "roughness": {})", rough), false},
      {R"("type": "dielectric")", true},
      {R"("type": "dielectric", "ior": 1, "roughness": 0.3)", true},
      {R"("type": "plastic", "roughness": 0.3)", false},
      {fmt::format(R"("type": "plastic", "roughness": {})", rough), false},
      {R"("type": "plastic", "roughness": 0)", true},
  };
  Pcg32 rng(17);
  for (const auto& c : cases) {
    const std::unique_ptr<Material> m = material_from_json(c.body);
    EXPECT_EQ(m->may_be_specular(), c.specular) << c.body;
    int specular = 0;
    for (int i = 0; i < 4000; ++i) {
      Arena arena;
      const SurfaceInteraction si = hit_at_uv(rng.next_float(), rng.next_float());
      const Bsdf* bsdf = m->bsdf(si, arena);
      const float cos_o = (i % 2 ? 1.0f : -1.0f) * (i % 4 < 2 ? 1.0f : 0.05f + 0.9f * rng.next_float());
      const float sin_o = std::sqrt(std::max(0.0f, 1.0f - cos_o * cos_o));
      const Vec3 wo(sin_o, 0.0f, cos_o);
      const BsdfSample bs = bsdf->sample(wo, rng.next_float(), Vec2(rng.next_float(), rng.next_float()));
      specular += bs.valid() && bs.delta();
      specular += (bsdf->flags() & kBsdfSpecular) != 0;
    }
    if (c.specular)
      EXPECT_GT(specular, 0) << c.body;
    else
      EXPECT_EQ(specular, 0) << c.body;
  }
}

}  // namespace
}  // namespace kozu::test
