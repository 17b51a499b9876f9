// Material surface occlusion (materials/surface_occlusion_material.h, materials/specular_occlusion_table.h; D. Chan,
// "Material Advances in Call of Duty: WWII", SIGGRAPH 2018 course Advances in Real-Time Rendering in Games, §4.6–4.7):
// the specular occlusion table against independent quadrature, its limits and monotonicity; eqs. (57)–(60); the
// direct factor in a scene against its closed form (light sampling and BSDF sampling under MIS both carry it); the
// scene keys, their errors and the visibility map built at load.
#include "materials/microfacet.h"
#include "materials/microfacet_albedo.h"
#include "materials/specular_occlusion_table.h"
#include "materials/surface_occlusion_material.h"
#include "support/render_test.h"
#include "support/sanitizer.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace kozu::test {
namespace {

using Table = SpecularOcclusionTable;

// ∫_{n·l > c_k} f_GGX(v, l) (n·l) dl (F = 1) for every cone node c_k, by the midpoint rule over (n·l, φ) on a grid of
// 7 m rows (the cone nodes fall on row boundaries) by 2 m columns over φ in [0, π] (the lobe is symmetric in φ):
// the integrand D(h) G2(v, l) / (4 n·v) on the directions l themselves, independent of the table's sampling.
std::array<double, Table::kCone> quadrature(float mu, float alpha, int m) {
  const MicrofacetDistribution d(MicrofacetType::GGX, alpha, alpha);
  const Vec3 v(std::sqrt(1.0f - mu * mu), 0.0f, mu);
  const int rows = 7 * m, cols = 2 * m;
  std::vector<double> row(size_t(rows), 0.0);
  for (int r = 0; r < rows; ++r) {
    const double z = (r + 0.5) / rows, s = std::sqrt(1 - z * z);
    double sum = 0;
    for (int c = 0; c < cols; ++c) {
      const double phi = M_PI * (c + 0.5) / cols;
      const Vec3 l(float(s * std::cos(phi)), float(s * std::sin(phi)), float(z));
      const Vec3 h = glm::normalize(v + l);
      sum += double(d.D(h)) * double(d.G2(v, l)) / (4.0 * mu);
    }
    row[size_t(r)] = 2 * sum * (M_PI / cols) / rows;  // dω = dz dφ, both halves of φ
  }
  std::array<double, Table::kCone> t{};
  for (int k = 0; k < Table::kCone; ++k)
    for (int r = k * m; r < rows; ++r) t[size_t(k)] += row[size_t(r)];
  return t;
}

TEST(SpecularOcclusionTable, NodesMatchQuadrature) {
  // Table nodes of μ (0.19, 0.52, 0.90) and gloss (0, 0.32, 0.48: α = 1, 0.19, 0.067), every cone node.
  for (int i : {6, 16, 28})
    for (int j : {0, 10, 15}) {
      const float mu = Table::mu_node(i), alpha = Table::alpha_of_gloss(Table::gloss_node(j));
      std::array<double, Table::kCone> t{}, se{};
      Table::integrate_node(mu, alpha, &t, &se);
      const auto q = quadrature(mu, alpha, 300), q_half = quadrature(mu, alpha, 150);
      for (int k = 0; k < Table::kCone; ++k) {
        // The table's error: 4 standard errors of its directions as plain Monte Carlo (Hammersley points do
        // better); the quadrature's: the change from half the grid (the midpoint rule's error falls 4-fold).
        const double tol = 4 * se[size_t(k)] + std::abs(q[size_t(k)] - q_half[size_t(k)]) + 1e-6;
        EXPECT_NEAR(Table::get().node(i, j, k), q[size_t(k)], tol) << "mu " << mu << " alpha " << alpha << " k " << k;
        EXPECT_NEAR(t[size_t(k)], Table::get().node(i, j, k), 1e-6);
      }
    }
}

// Slice 0 (the open hemisphere) is the ordinary directional albedo of a GGX conductor with F = 1, integrated
// independently (materials/microfacet_albedo.h's jittered grid of visible normals; at gloss > 0.5, α < 0.06, that
// integrator's single-precision directions lose up to 2.4e-4 of the albedo, measured against this table's 1 - 1e-5
// near the normal, so a floor of 5e-4 is added there); slice 7 (closed) is 0.
TEST(SpecularOcclusionTable, FullConeIsTheAlbedoAndClosedConeIsBlack) {
  const Table& table = Table::get();
  for (int i = 1; i < Table::kMu; i += 3)
    for (int j = 0; j < Table::kGloss; j += 3) {
      const float mu = Table::mu_node(i), alpha = Table::alpha_of_gloss(Table::gloss_node(j));
      std::array<double, Table::kCone> t{}, se{};
      Table::integrate_node(mu, alpha, &t, &se);
      const double e = albedo::integrate_conductor(MicrofacetDistribution(MicrofacetType::GGX, alpha, alpha), mu, 128);
      // Both estimates' errors: the table's 4 standard errors; the albedo's grid has 4 times the points.
      EXPECT_NEAR(table.node(i, j, 0), e, 4 * se[0] * 1.5 + (j <= 15 ? 1e-5 : 5e-4))
          << "mu " << mu << " alpha " << alpha;
      EXPECT_EQ(table.node(i, j, Table::kCone - 1), 0.0f);
      EXPECT_FLOAT_EQ(specular_occlusion(mu, Table::gloss_node(j), 0.0f), 1.0f);
      EXPECT_EQ(specular_occlusion(mu, Table::gloss_node(j), 1.0f), 0.0f);
    }
}

TEST(SpecularOcclusionTable, MonotoneInTheConeAngle) {
  const Table& table = Table::get();
  for (int i = 0; i < Table::kMu; ++i)
    for (int j = 0; j < Table::kGloss; ++j)
      for (int k = 1; k < Table::kCone; ++k) ASSERT_LE(table.node(i, j, k), table.node(i, j, k - 1)) << i << j << k;
  // Between nodes too, and a rough lobe is occluded more than a glossy one seen along the normal (its light comes
  // from all over the hemisphere, the glossy lobe's from near the normal).
  for (float mu : {0.3f, 0.77f, 1.0f}) {
    float prev = 1.0f;
    for (float c = 0.0f; c <= 1.0f; c += 0.01f) {
      const float r = specular_occlusion(mu, 0.6f, c);
      EXPECT_LE(r, prev + 1e-6f);
      prev = r;
    }
  }
  EXPECT_LT(specular_occlusion(1.0f, 0.0f, 0.5f), specular_occlusion(1.0f, 0.8f, 0.5f));
  // A cosine lobe inside the equal-area cone keeps V = 1 - c² (eq. 54); the roughest GGX lobe (α = 1) is near it.
  EXPECT_NEAR(specular_occlusion(1.0f, 0.0f, 0.5f), 0.75f, 0.1f);
}

TEST(SurfaceOcclusion, ConeFactorsEq57And58) {
  // eq. (58): clamp(n·l / cos θ, 0, 1)².
  EXPECT_FLOAT_EQ(SurfaceOcclusion::smooth_cone(0.5f, 0.25f), 0.25f);
  EXPECT_FLOAT_EQ(SurfaceOcclusion::smooth_cone(0.5f, 0.5f), 1.0f);
  EXPECT_FLOAT_EQ(SurfaceOcclusion::smooth_cone(0.5f, 0.9f), 1.0f);
  EXPECT_FLOAT_EQ(SurfaceOcclusion::smooth_cone(0.8f, -0.1f), 0.0f);
  EXPECT_FLOAT_EQ(SurfaceOcclusion::smooth_cone(0.0f, 0.01f), 1.0f);  // V = 1: the open hemisphere
  // eq. (57): 1 where cos θ < n·l.
  EXPECT_EQ(SurfaceOcclusion::hard_cone(0.5f, 0.49f), 0.0f);
  EXPECT_EQ(SurfaceOcclusion::hard_cone(0.5f, 0.51f), 1.0f);
  // Cosine-weighted over the hemisphere: eq. (57) keeps V = 1 - c² (the equal-area cone), eq. (58) 1 - c²/2.
  for (float c : {0.2f, 0.5f, 0.9f}) {
    double hard = 0, smooth = 0;
    const int n = 100000;
    for (int s = 0; s < n; ++s) {
      const float mu = (s + 0.5f) / n;
      hard += 2 * mu * SurfaceOcclusion::hard_cone(c, mu) / n;
      smooth += 2 * mu * SurfaceOcclusion::smooth_cone(c, mu) / n;
    }
    EXPECT_NEAR(hard, 1 - c * c, 1e-4);
    EXPECT_NEAR(smooth, 1 - c * c / 2, 1e-4);
  }
}

// Which factor each sampled lobe's continuation gets (cone cos 0.6: V = 0.64).
TEST(SurfaceOcclusion, IndirectFactorPerLobe) {
  const auto make = [](SurfaceOcclusion::Specular specular, float gloss, float albedo) {
    SurfaceOcclusion::Settings s;
    s.specular = specular;
    s.gloss = gloss;
    s.albedo = albedo;
    return SurfaceOcclusion(std::make_unique<ConstantTexture>(Rgb(0.64f)), s);
  };
  const float c = 0.6f;
  const SurfaceOcclusion table = make(SurfaceOcclusion::Specular::Table, 0.4f, 0.0f);
  EXPECT_FLOAT_EQ(table.indirect(c, 0.7f, 0.5f, kBsdfReflection | kBsdfGlossy), specular_occlusion(0.7f, 0.4f, c));
  EXPECT_NEAR(table.indirect(c, 0.7f, 0.5f, kBsdfReflection | kBsdfDiffuse), 0.64f, 1e-6f);  // eq. (54): V
  EXPECT_EQ(table.indirect(c, 0.7f, 0.5f, kBsdfReflection | kBsdfSpecular), 0.0f);           // outside the cone
  EXPECT_EQ(table.indirect(c, 0.7f, 0.7f, kBsdfReflection | kBsdfSpecular), 1.0f);
  EXPECT_EQ(table.indirect(c, 0.7f, 0.5f, kBsdfTransmission | kBsdfGlossy), 1.0f);
  float g = 0;
  EXPECT_FLOAT_EQ(
      make(SurfaceOcclusion::Specular::Game, 0.4f, 0.0f).indirect(c, 0.7f, 0.5f, kBsdfReflection | kBsdfGlossy),
      specular_occlusion(0.7f, 0.4f, game_cone_cos(c, 0.7f, 0.4f, &g)));
  // "specular": "off" leaves glossy continuations alone whether or not a gloss is known.
  EXPECT_EQ(make(SurfaceOcclusion::Specular::Off, -1.0f, 0.0f).indirect(c, 0.7f, 0.5f, kBsdfReflection | kBsdfGlossy),
            1.0f);
  // eq. (49) with albedo 0.5: A' = V / (1 - ρ + ρ V).
  EXPECT_NEAR(
      make(SurfaceOcclusion::Specular::Table, 0.4f, 0.5f).indirect(c, 0.7f, 0.5f, kBsdfReflection | kBsdfDiffuse),
      0.64f / (0.5f + 0.5f * 0.64f), 1e-6f);
}

TEST(SurfaceOcclusion, GameBiasesEq59And60) {
  float g = 0;
  // eq. (60): gloss' = clamp(1.5 gloss, 0, 1); eq. (59): cos θ' = cos θ (1 - gloss'²) (n·v)⁴.
  EXPECT_FLOAT_EQ(game_cone_cos(0.8f, 1.0f, 0.4f, &g), 0.8f * (1 - 0.36f));
  EXPECT_FLOAT_EQ(g, 0.6f);
  EXPECT_FLOAT_EQ(game_cone_cos(0.8f, 0.5f, 0.0f, &g), 0.8f * 0.0625f);
  EXPECT_EQ(game_cone_cos(0.8f, 1.0f, 0.7f, &g), 0.0f);  // gloss' = 1: the cone opens fully
}

// A plane under a uniform sky L, diffuse albedo ρ, a flat normal map and a constant visibility V (cone cos c),
// direct light only: eq. (58) gives ρ L (1 - c²/2), eq. (57) ρ L (1 - c²). The sky reaches the plane both by light
// sampling and by BSDF-sampled rays, weighted by MIS: a factor missing on either would move the mean.
std::string sky_plane(const std::string& occlusion) {
  return fmt::format(R"({{"camera": {{"type": "orthographic", "position": [0, 0, 5], "look_at": [0, 0, 0],
                                        "scale": 1, "resolution": [16, 16]}},
    "render": {{"max_depth": 1}},
    "materials": {{"m": {{"type": "diffuse", "albedo": 0.5,
                          "normal_map": {{"type": "constant", "value": [0.5, 0.5, 1]}}{}}}}},
    "shapes": [{{"type": "quad", "material": "m", "vertices": [[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]]}}],
    "lights": [{{"type": "environment", "radiance": 2}}]}})",
                     occlusion);
}

TEST(SurfaceOcclusion, SkyOnAPlaneMatchesTheClosedForm) {
  const int spp = kSanitized ? 64 : 256;
  for (const auto& [keys, expected] :
       {std::pair{std::string(""), 1.0}, std::pair{std::string(R"(, "surface_occlusion": {"ao": 0.75})"), 0.875},
        std::pair{std::string(R"(, "surface_occlusion": {"ao": 0.75, "direct": "hard"})"), 0.75},
        std::pair{std::string(R"(, "surface_occlusion": {"ao": 0.75, "mode": "off"})"), 1.0}}) {
    const TestRender r = render_json(sky_plane(keys), spp, 0, 7);
    const ImageStats s = image_stats(r.film);
    EXPECT_NEAR(s.mean.g, expected, 5 * s.standard_error.g + 1e-4) << keys;
  }
}

std::string error_of(const std::string& material) {
  const std::string scene = fmt::format(R"({{"camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0],
    "resolution": [4, 4]}}, "materials": {{"m": {}}},
    "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}}]}})",
                                        material);
  try {
    render_json(scene, 1);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(SurfaceOcclusion, BadInputIsOneLineWithItsPath) {
  const std::string nm = R"("normal_map": {"type": "constant", "value": [0.5, 0.5, 1]})";
  std::string e = error_of(R"({"type": "diffuse", "surface_occlusion": true})");
  EXPECT_NE(e.find("/materials/m/surface_occlusion"), std::string::npos) << e;
  EXPECT_NE(e.find("'surface_occlusion' needs a 'normal_map'"), std::string::npos) << e;
  e = error_of(R"({"type": "diffuse", )" + nm + R"(, "surface_occlusion": {"mode": "cones", "ao": 1}})");
  EXPECT_NE(e.find("/materials/m/surface_occlusion/mode"), std::string::npos) << e;
  e = error_of(R"({"type": "diffuse", )" + nm + R"(, "surface_occlusion": {"ao": 1, "specullar": "off"}})");
  EXPECT_NE(e.find("specullar"), std::string::npos) << e;
  EXPECT_NE(e.find("/materials/m/surface_occlusion"), std::string::npos) << e;
  e = error_of(R"({"type": "diffuse", )" + nm + R"(, "surface_occlusion": {"ao": 1.5}})");
  EXPECT_NE(e.find("/materials/m/surface_occlusion/ao"), std::string::npos) << e;
  e = error_of(R"({"type": "diffuse", )" + nm + R"(, "surface_occlusion": 3})");
  EXPECT_NE(e.find("expected true, false or an object"), std::string::npos) << e;
  // A constant normal map has no texels to compute the visibility from.
  e = error_of(R"({"type": "diffuse", )" + nm + R"(, "surface_occlusion": true})");
  EXPECT_NE(e.find("give \"ao\""), std::string::npos) << e;
  // The table needs the material's gloss.
  e = error_of(R"({"type": "conductor", "roughness": {"type": "constant", "value": 0.3}, )" + nm +
               R"(, "surface_occlusion": {"ao": 1}})");
  EXPECT_NE(e.find("needs the material's gloss"), std::string::npos) << e;
  EXPECT_EQ(error_of(R"({"type": "conductor", "roughness": 0.3, )" + nm + R"(, "surface_occlusion": {"ao": 1}})"), "");
  EXPECT_EQ(error_of(R"({"type": "diffuse", )" + nm + R"(, "surface_occlusion": false})"), "");
  for (const std::string& m : {std::string(R"({"type": "diffuse", "surface_occlusion": true})"),
                               R"({"type": "diffuse", )" + nm + R"(, "surface_occlusion": 3})"})
    EXPECT_EQ(error_of(m).find('\n'), std::string::npos) << error_of(m);
}

// Without "ao" the visibility is computed from the normal map at load, written once into the texture cache's
// folder and reused: a flat map gives V = 1 (the plane as without occlusion).
TEST(SurfaceOcclusion, VisibilityIsBuiltOnceFromTheNormalMap) {
  TempDir dir;
  const auto map =
      write_test_exr(dir.path() / "flat.exr", 32, 32, [](int, int, int c) { return c == 2 ? 1.0f : 0.5f; });
  const std::string scene = fmt::format(R"({{"camera": {{"type": "orthographic", "position": [0, 0, 5],
      "look_at": [0, 0, 0], "scale": 1, "resolution": [8, 8]}}, "render": {{"max_depth": 1}},
    "materials": {{"m": {{"type": "diffuse", "albedo": 0.5, "normal_map": {{"type": "image", "file": "{}"}},
                          "surface_occlusion": {{"direct": "hard"}}}}}},
    "shapes": [{{"type": "quad", "material": "m", "vertices": [[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]]}}],
    "lights": [{{"type": "environment", "radiance": 2}}]}})",
                                        map.string());
  const TestRender a = render_json(scene, 64, 0, 3);
  std::vector<std::filesystem::path> built;
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / "kozu-tx";
  for (const auto& e : std::filesystem::directory_iterator(folder))
    if (e.path().filename().string().starts_with("flat-") && e.path().string().ends_with(".ao.exr"))
      built.push_back(e.path());
  ASSERT_FALSE(built.empty());
  const ImageStats s = image_stats(a.film);
  EXPECT_NEAR(s.mean.g, 1.0, 5 * s.standard_error.g + 1e-4);
  // Changed (a new modification time), the map gets a new file; the old one is not read again.
  std::filesystem::last_write_time(map, std::filesystem::last_write_time(map) + std::chrono::seconds(5));
  const TestRender b = render_json(scene, 1, 0, 3);
  size_t n = 0;
  for (const auto& e : std::filesystem::directory_iterator(folder))
    if (e.path().filename().string().starts_with("flat-") && e.path().string().ends_with(".ao.exr")) ++n;
  EXPECT_EQ(n, built.size() + 1);
}

// From the command line with relative paths: `kozu render sub/scene.json -o sub/out.exr` puts the texture cache in
// sub/.kozu-tx, a relative folder; the computed map's path must not be resolved against the scene's folder again.
TEST(SurfaceOcclusion, RelativeCacheFolderFromTheCommandLine) {
  TempDir dir;
  const RelativeCacheRender r = render_with_relative_cache(
      dir, R"({"type": "diffuse", "normal_map": {"type": "image", "file": "bumps.exr"}, "surface_occlusion": true})");
  EXPECT_EQ(r.status, 0) << r.output;
  const auto maps =
      std::count_if(r.cached.begin(), r.cached.end(), [](const std::string& f) { return f.ends_with(".ao.exr"); });
  EXPECT_EQ(maps, 1);
}

// With normal_gloss_filtering (on by default for a rough conductor's image map) the material is parsed from the
// filtered description: the key is read there, and the visibility still comes from the scene's own map.
TEST(SurfaceOcclusion, WorksWithNormalGlossFiltering) {
  TempDir dir;
  const auto map = write_test_exr(dir.path() / "ridges.exr", 32, 32, [](int x, int, int c) {
    const double s = 1.2 * std::sin(2 * M_PI * (x + 0.5) / 8), len = std::sqrt(1 + s * s);
    return float(0.5 * ((c == 0 ? -s : c == 1 ? 0.0 : 1.0) / len + 1));
  });
  const auto scene = [&](const std::string& keys) {
    return fmt::format(R"({{"camera": {{"type": "orthographic", "position": [0, 0, 5], "look_at": [0, 0, 0],
        "scale": 1, "resolution": [8, 8]}}, "render": {{"max_depth": 1}},
      "materials": {{"m": {{"type": "conductor", "roughness": 0.5, "normal_map": {{"type": "image", "file": "{}"}}{}}}}},
      "shapes": [{{"type": "quad", "material": "m", "vertices": [[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]]}}],
      "lights": [{{"type": "environment", "radiance": 2}}]}})",
                       map.string(), keys);
  };
  const TestRender plain = render_json(scene(""), 64, 0, 3);
  const TestRender occluded = render_json(scene(R"(, "surface_occlusion": {"direct": "hard"})"), 64, 0, 3);
  EXPECT_LT(image_stats(occluded.film).mean.g, 0.98f * image_stats(plain.film).mean.g);
}

}  // namespace
}  // namespace kozu::test
