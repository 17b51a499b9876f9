// White furnace with a textured roughness (materials/roughness.h, roughness_tables.h): a conductor with F = 1 (no
// eta) and "multiscatter": "compensated" whose roughness is a checker keeps albedo 1 in both squares, at levels on
// and off the 1/255 steps, with the tolerance of tests/materials/test_rough_materials.cpp's WhiteFurnace (1 %);
// and so does a plastic with a white base (the compensation tables of each rounded level are the BSDF's own).
#include "support/bsdf_test.h"

#include "core/arena.h"
#include "core/json_reader.h"
#include "materials/material.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

namespace kozu::test {
namespace {

struct Levels {
  float a, b;  // the checker's two values
};

class TexturedFurnace : public ::testing::TestWithParam<Levels> {};

void expect_white(const std::string& body, const std::string& name) {
  const auto material = material_from_json(body);
  double worst = 0.0;
  for (const Vec2 square : {Vec2(0.25f, 0.25f), Vec2(0.75f, 0.25f)}) {
    Arena arena;
    const Bsdf* bsdf = material->bsdf(hit_at_uv(square.x, square.y), arena);
    for (const double theta : {0.0, 30.0, 60.0, 80.0}) {
      const AlbedoEstimate e =
          directional_albedo(*bsdf, direction_from_angles(theta, 20.0), TransportMode::Radiance, 77 + uint64_t(theta));
      const std::string where = fmt::format("{} u {} theta {}", name, square.x, theta);
      EXPECT_LT(max_rgb(e.se), 1.5e-3) << where;
      EXPECT_NEAR(e.mean.g, 1.0, 0.01) << where;  // test_rough_materials.cpp WhiteFurnace's law "One"
      worst = std::max(worst, std::abs(e.mean.g - 1.0));
    }
  }
  fmt::print("[albedo] {:<32} largest |albedo - 1| {:.4f}\n", name, worst);
}

TEST_P(TexturedFurnace, ConductorAlbedoOne) {
  const Levels l = GetParam();
  for (const char* key : {"roughness", "alpha"})
    expect_white(fmt::format(R"("type": "conductor", "multiscatter": "compensated", "{}": {{"type": "checker",
                                "scale": [2, 2], "a": {}, "b": {}}})",
                             key, l.a, l.b),
                 fmt::format("conductor {} {}/{}", key, l.a, l.b));
}

TEST_P(TexturedFurnace, PlasticWhiteAlbedoOne) {
  const Levels l = GetParam();
  expect_white(fmt::format(R"("type": "plastic", "albedo": 1, "roughness": {{"type": "checker", "scale": [2, 2],
                              "a": {}, "b": {}}})",
                           l.a, l.b),
               fmt::format("plastic {}/{}", l.a, l.b));
}

// On the 1/255 steps and between them (0.333 and 0.777 are rounded to 85/255 and 198/255).
INSTANTIATE_TEST_SUITE_P(Levels, TexturedFurnace,
                         ::testing::Values(Levels{0.2f, 0.6f}, Levels{0.333f, 0.777f}, Levels{0.05f, 1.0f}));

}  // namespace
}  // namespace kozu::test
