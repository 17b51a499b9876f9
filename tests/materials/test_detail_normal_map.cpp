// Detail normal maps (materials/detail_normal_blend.h, materials/normal_map.h): BlendXY (D. Chan, "Material
// Advances in Call of Duty: WWII", SIGGRAPH 2018 course Advances in Real-Time Rendering in Games, §2.4, Algorithm 4)
// and reoriented normal mapping (Barré-Brisebois & Hill 2012, "Blending in Detail"), their keys and a render.
#include "support/render_test.h"

#include "core/rng.h"
#include "materials/detail_normal_blend.h"
#include "materials/normal_map.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>

namespace kozu::test {
namespace {

constexpr Vec3 kZ(0.0f, 0.0f, 1.0f);

// A unit normal within 60 degrees of +z, from a fixed-seed generator.
Vec3 random_normal(Pcg32& rng) {
  const float cos_t = 1.0f - 0.5f * rng.next_float(), phi = 2.0f * kPi * rng.next_float();
  const float sin_t = std::sqrt(1.0f - cos_t * cos_t);
  return Vec3(sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t);
}

void expect_vec_near(const Vec3& a, const Vec3& b, float tol) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

TEST(DetailNormalBlend, FlatDetailLeavesTheBaseUnchanged) {
  Pcg32 rng(7);
  for (int i = 0; i < 200; ++i) {
    const Vec3 b = random_normal(rng);
    expect_vec_near(blend_xy(b, kZ), b, 1e-6f);
    expect_vec_near(blend_rnm(b, kZ), b, 1e-6f);
  }
}

TEST(DetailNormalBlend, FlatBaseGivesTheDetail) {
  Pcg32 rng(8);
  for (int i = 0; i < 200; ++i) {
    const Vec3 d = random_normal(rng);
    expect_vec_near(blend_xy(kZ, d), d, 1e-6f);
    expect_vec_near(blend_rnm(kZ, d), d, 1e-6f);
  }
}

// RNM is the detail rotated by the shortest-arc rotation taking +z to the base: here built independently, as the
// Rodrigues matrix R = I + sin(a) K + (1 - cos(a)) K^2 of the axis k = normalize(z x b) and angle a = acos(b_z).
TEST(DetailNormalBlend, RnmRotatesTheDetailByTheBaseRotation) {
  Pcg32 rng(9);
  for (int i = 0; i < 500; ++i) {
    const glm::dvec3 b = glm::normalize(glm::dvec3(random_normal(rng))), d(random_normal(rng));
    const glm::dvec3 axis = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), b));
    const double a = std::acos(b.z);
    const glm::dmat3 k(0, axis.z, -axis.y, -axis.z, 0, axis.x, axis.y, -axis.x, 0);  // columns: K v = axis x v
    const glm::dmat3 r = glm::dmat3(1.0) + std::sin(a) * k + (1.0 - std::cos(a)) * (k * k);
    ASSERT_NEAR(glm::length(r * glm::dvec3(0, 0, 1) - b), 0.0, 1e-12);  // the matrix takes +z to b
    const glm::dvec3 expected = r * d;
    expect_vec_near(blend_rnm(Vec3(b), Vec3(d)), Vec3(expected), 2e-6f);
    EXPECT_NEAR(glm::length(blend_rnm(Vec3(b), Vec3(d))), 1.0f, 1e-6f);
  }
}

// Algorithm 4 by hand: the offsets add, z = sqrt(1 - x^2 - y^2).
TEST(DetailNormalBlend, BlendXyHandComputed) {
  const Vec3 b(0.3f, -0.2f, std::sqrt(1.0f - 0.13f)), d(0.1f, 0.4f, std::sqrt(1.0f - 0.17f));
  expect_vec_near(blend_xy(b, d), Vec3(0.4f, 0.2f, std::sqrt(0.8f)), 1e-6f);
  // Not normalised inputs are normalised first: twice the vectors give the same blend.
  expect_vec_near(blend_xy(2.0f * b, 0.5f * d), Vec3(0.4f, 0.2f, std::sqrt(0.8f)), 1e-6f);
  // Offsets beyond the unit disc: onto the horizon, (1.4, 0) -> (1, 0, 0).
  expect_vec_near(blend_xy(Vec3(0.8f, 0.0f, 0.6f), Vec3(0.6f, 0.0f, 0.8f)), Vec3(1.0f, 0.0f, 0.0f), 1e-6f);
  // The two blends differ away from flat inputs: RNM of the same pair (from its closed form) is not BlendXY's.
  EXPECT_GT(glm::length(blend_rnm(b, d) - blend_xy(b, d)), 1e-3f);
}

// The map decodes both texels alike (convention included) and hands the blend to the frame.
TEST(DetailNormalBlend, NormalMapBlendsInTangentSpace) {
  const Vec3 b = glm::normalize(Vec3(0.2f, 0.1f, 1.0f)), d = glm::normalize(Vec3(-0.3f, 0.25f, 1.0f));
  const auto encode = [](const Vec3& m) { return Rgb(0.5f * (m.x + 1.0f), 0.5f * (m.y + 1.0f), 0.5f * (m.z + 1.0f)); };
  for (const DetailBlend blend : {DetailBlend::BlendXY, DetailBlend::Rnm}) {
    const NormalMap map(std::make_unique<ConstantTexture>(encode(b)), 1.0f, false,
                        std::make_unique<ConstantTexture>(encode(d)), blend);
    EXPECT_TRUE(map.has_detail());
    expect_vec_near(map.blended_tangent_normal(encode(b), encode(d)), blend_detail_normal(blend, b, d), 1e-6f);
    // In a rotated frame (t, b, n) = (y, -x, z), w = 1: the tangent-space result's coordinates along it.
    const Vec3 m = blend_detail_normal(blend, b, d);
    const Vec3 n = map.perturbed_normal(encode(b), encode(d), Vec3(0, 1, 0), 1.0f, Vec3(0, 0, 1));
    expect_vec_near(n, m.x * Vec3(0, 1, 0) + m.y * Vec3(-1, 0, 0) + m.z * Vec3(0, 0, 1), 1e-6f);
    // DirectX convention: y negated in both texels before the blend.
    const NormalMap dx(std::make_unique<ConstantTexture>(encode(b)), 1.0f, true,
                       std::make_unique<ConstantTexture>(encode(d)), blend);
    const Vec3 flip(1.0f, -1.0f, 1.0f);
    expect_vec_near(dx.blended_tangent_normal(encode(b), encode(d)), blend_detail_normal(blend, b * flip, d * flip),
                    1e-6f);
  }
}

std::string sphere_scene(const std::string& material) {
  return fmt::format(R"({{"camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0], "resolution": [4, 4]}},
    "materials": {{"m": {}}},
    "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}}]}})",
                     material);
}

void expect_error(const std::string& material, const std::string& message) {
  try {
    render_json(sphere_scene(material), 1);
    ADD_FAILURE() << "accepted " << material;
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
  }
}

TEST(DetailNormalMap, KeysAreChecked) {
  expect_error(R"({"type": "diffuse", "detail_normal_map": [0.5, 0.5, 1]})",
               "'detail_normal_map' needs a 'normal_map'");
  expect_error(R"({"type": "diffuse", "detail_blend": "rnm"})", "'detail_blend' needs a 'normal_map'");
  expect_error(R"({"type": "diffuse", "normal_map": [0.5, 0.5, 1], "detail_blend": "rnm"})",
               "'detail_blend' needs a 'detail_normal_map'");
  expect_error(R"({"type": "diffuse", "normal_map": [0.5, 0.5, 1], "detail_normal_map": [0.5, 0.5, 1],
                   "detail_blend": "udn"})",
               "detail_blend");
  expect_error(R"({"type": "diffuse", "normal_map": [0.5, 0.5, 1], "detail_gloss": "fit"})",
               "'detail_gloss' needs a 'detail_normal_map'");
  expect_error(R"({"type": "diffuse", "normal_map": [0.5, 0.5, 1], "detail_normal_map": [0.5, 0.5, 1],
                   "detail_gloss": "lut"})",
               "detail_gloss");
  expect_error(R"({"type": "diffuse", "normal_map": [0.5, 0.5, 1], "detail_normal_map": [0.5, 0.5, 2]})",
               "detail_normal_map");
}

// A floor lit by a small light: a bumpy detail map (its own uv_scale) over a flat base map changes the image; a flat
// detail map changes no bit.
std::string floor_scene(const std::string& base, const std::string& detail_keys) {
  return fmt::format(R"({{"camera": {{"position": [0, -3, 2], "look_at": [0, 0, 0], "up": [0, 0, 1], "fov": 40,
                                       "resolution": [24, 16]}},
    "materials": {{"floor": {{"type": "conductor", "roughness": 0.2, "normal_gloss_filtering": false,
                              "normal_map": {{"type": "image", "file": "{}", "filter": "closest"}}{}}}}},
    "shapes": [{{"type": "quad", "material": "floor", "vertices": [[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]]}},
               {{"type": "sphere", "center": [0, 2, 1.5], "radius": 0.3, "emission": 20}}]}})",
                     base, detail_keys);
}

TEST(DetailNormalMap, ADetailMapChangesTheRender) {
  TempDir dir;
  const auto flat = write_test_exr(dir.path() / "flat.exr", 4, 4, [](int, int, int c) { return c == 2 ? 1.0f : 0.5f; });
  // Ridges along x: slope 0.5 sin, encoded (x, 0, z).
  const auto ridges = write_test_exr(dir.path() / "ridges.exr", 16, 16, [](int x, int, int c) {
    const float s = 0.5f * std::sin(2.0f * kPi * (x + 0.5f) / 16.0f);
    const Vec3 n = glm::normalize(Vec3(-s, 0.0f, 1.0f));
    return 0.5f * (n[c] + 1.0f);
  });
  const TestRender none = render_json(floor_scene(flat.string(), ""), 4, 0, 1);
  for (const char* blend : {"blendxy", "rnm"}) {
    SCOPED_TRACE(blend);
    const TestRender same = render_json(
        floor_scene(flat.string(),
                    fmt::format(R"(, "detail_blend": "{}", "detail_normal_map": {{"type": "image", "file": "{}",
                                   "filter": "closest", "uv_scale": [3, 3]}})",
                                blend, flat.string())),
        4, 0, 1);
    const TestRender bumpy = render_json(
        floor_scene(flat.string(),
                    fmt::format(R"(, "detail_blend": "{}", "detail_normal_map": {{"type": "image", "file": "{}",
                                   "filter": "closest", "uv_scale": [3, 3]}})",
                                blend, ridges.string())),
        4, 0, 1);
    double changed = 0, total = 0;
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 24; ++x) {
        ASSERT_EQ(same.film.mean(x, y).g, none.film.mean(x, y).g) << x << ", " << y;
        changed += std::abs(bumpy.film.mean(x, y).g - none.film.mean(x, y).g);
        total += none.film.mean(x, y).g;
      }
    fmt::print("{}: mean |difference| / mean = {:.3f}\n", blend, changed / total);
    EXPECT_GT(changed, 0.1 * total);
  }
}

}  // namespace
}  // namespace kozu::test
