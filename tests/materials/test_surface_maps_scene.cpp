// Scene-level checks of the keys every surface material accepts: a normal-mapped plane in a white furnace.
//
// Furnace: a white Lambertian plane (albedo 1) under a uniform environment of radiance 1, seen from above with a
// narrow field of view, so every pixel shows the plane. With a flat normal map every pixel is 1. A map tilted by
// an angle a (±a towards either tangent axis) keeps the viewer above the tilted normal, and the
// integrator's guard (integrators/path.cpp) drops the part of the tilted cosine lobe below the geometric horizon,
// the fraction (1 − cos a) / 2 (materials/shading_normal.h): the image mean must be 1 − (1 − cos a) / 2, no more
// (no light created or let through) and no less. Tolerance: 5 standard errors of the image mean.
#include "support/render_test.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace kozu::test {
namespace {

std::string furnace_plane(const std::string& extra_material_keys) {
  return fmt::format(R"({{"camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 20,
                                       "resolution": [24, 24]}},
    "render": {{"max_depth": 16}},
    "materials": {{"white": {{"type": "diffuse", "albedo": 1{}}}}},
    "shapes": [{{"type": "quad", "material": "white",
                 "vertices": [[-20, -20, 0], [20, -20, 0], [20, 20, 0], [-20, 20, 0]]}}],
    "lights": [{{"type": "environment", "radiance": 1}}]}})",
                     extra_material_keys);
}

// The texel encoding the unit tangent-space normal tilted by a towards +X (axis 0) or +Y (axis 1).
std::string tilted_texel(float a, int axis, float sign) {
  const float s = 0.5f * (1.0f + sign * std::sin(a)), c = 0.5f * (1.0f + std::cos(a));
  return axis == 0 ? fmt::format("[{:.9g}, 0.5, {:.9g}]", s, c) : fmt::format("[0.5, {:.9g}, {:.9g}]", s, c);
}

TEST(NormalMapFurnace, FlatMapRendersOne) {
  const TestRender r =
      render_json(furnace_plane(R"(, "normal_map": {"type": "constant", "value": [0.5, 0.5, 1]})"), 64, 0, 3);
  const ImageStats s = image_stats(r.film);
  fmt::print("flat normal map: {:.5f} +- {:.5f}\n", s.mean.g, s.standard_error.g);
  EXPECT_NEAR(s.mean.g, 1.0, 5.0 * s.standard_error.g + 1e-4);
}

TEST(NormalMapFurnace, TiltedMapLosesOnlyTheLobeBelowTheHorizon) {
  for (const float deg : {15.0f, 30.0f, 50.0f})
    for (int axis = 0; axis < 2; ++axis)
      for (const float sign : {1.0f, -1.0f}) {
        const float a = deg * kPi / 180.0f;
        const std::string map =
            fmt::format(R"(, "normal_map": {{"type": "constant", "value": {}}})", tilted_texel(a, axis, sign));
        const TestRender r = render_json(furnace_plane(map), 64, 0, 5);
        const ImageStats s = image_stats(r.film);
        const double expected = 1.0 - (1.0 - std::cos(a)) / 2.0;
        fmt::print("tilt {}{} deg about axis {}: {:.5f} +- {:.5f} (expected {:.5f})\n", sign > 0 ? "+" : "-", deg, axis,
                   s.mean.g, s.standard_error.g, expected);
        EXPECT_NEAR(s.mean.g, expected, 5.0 * s.standard_error.g + 1e-4) << deg << " degrees, axis " << axis;
      }
}

// ---------------------------------------------------------------------------------------------
// Opacity cut-outs (materials/opacity_mask.h).

// A leaf quad [-1, 1]² at z = 1 over a ground, lit by a small sphere light (shadow rays) and a dim environment
// (bounce rays); `leaf_shapes` are the leaf's quads, `leaf_keys` extra keys of its material.
std::string leaf_scene(const std::string& leaf_shapes, const std::string& leaf_keys) {
  return fmt::format(R"({{"camera": {{"position": [0.3, -3, 4], "look_at": [0, 0, 0.3], "fov": 45,
                                       "resolution": [40, 40]}},
    "render": {{"max_depth": 8}},
    "materials": {{"ground": {{"type": "diffuse", "albedo": 0.8}},
                   "leaf": {{"type": "diffuse", "albedo": [0.2, 0.6, 0.2]{}}}}},
    "shapes": [{{"type": "quad", "material": "ground", "vertices": [[-4, -4, 0], [4, -4, 0], [4, 4, 0], [-4, 4, 0]]}},
               {{"type": "sphere", "center": [0.6, 0.8, 4], "radius": 0.4, "emission": 20}}{}],
    "lights": [{{"type": "environment", "radiance": 0.2}}]}})",
                     leaf_keys, leaf_shapes);
}

std::string leaf_quad(float x0, float y0, float x1, float y1) {
  return fmt::format(
      R"(, {{"type": "quad", "material": "leaf", "vertices": [[{0}, {1}, 1], [{2}, {1}, 1], [{2}, {3}, 1],
                     [{0}, {3}, 1]]}})",
      x0, y0, x1, y1);
}

struct Comparison {
  double mean_diff = 0, mean_se = 0;
  int outliers = 0, pixels = 0;  // pixels whose difference exceeds 4.5 standard errors (green channel)
};

Comparison compare(const Film& a, const Film& b) {
  Comparison c;
  const ImageStats sa = image_stats(a), sb = image_stats(b);
  c.mean_diff = sa.mean.g - sb.mean.g;
  c.mean_se = std::hypot(sa.standard_error.g, sb.standard_error.g);
  for (int y = 0; y < a.height(); ++y)
    for (int x = 0; x < a.width(); ++x) {
      const double d = a.mean(x, y).g - b.mean(x, y).g;
      const double se = std::sqrt(a.variance_of_mean(x, y).g + b.variance_of_mean(x, y).g);
      ++c.pixels;
      if (std::abs(d) > 4.5 * se + 1e-6) ++c.outliers;
    }
  return c;
}

// A checker opacity of 1 and 0 (4 × 4 cells, opaque where i + j is even) renders as the same leaf cut into its 8
// opaque squares: the image means agree within 5 standard errors and (nearly) no pixel differs by more than 4.5
// (independent seeds). A solid leaf, the control, must fail the same comparison.
TEST(OpacityScene, CheckerCutOutMatchesSeparateQuads) {
  const TestRender cut = render_json(
      leaf_scene(leaf_quad(-1, -1, 1, 1), R"(, "opacity": {"type": "checker", "scale": [4, 4], "a": 1, "b": 0})"), 64,
      0, 3);
  std::string squares;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i)
      if ((i + j) % 2 == 0)
        squares += leaf_quad(-1.0f + 0.5f * i, -1.0f + 0.5f * j, -0.5f + 0.5f * i, -0.5f + 0.5f * j);
  const TestRender ref = render_json(leaf_scene(squares, ""), 64, 0, 4);
  const TestRender solid = render_json(leaf_scene(leaf_quad(-1, -1, 1, 1), ""), 64, 0, 4);
  const Comparison c = compare(cut.film, ref.film), control = compare(cut.film, solid.film);
  fmt::print("cut-out vs squares: mean diff {:.5f} +- {:.5f}, {} of {} pixels beyond 4.5 se\n", c.mean_diff, c.mean_se,
             c.outliers, c.pixels);
  fmt::print("cut-out vs solid leaf (control): mean diff {:.5f} +- {:.5f}, {} pixels beyond 4.5 se\n",
             control.mean_diff, control.mean_se, control.outliers);
  EXPECT_LT(std::abs(c.mean_diff), 5.0 * c.mean_se);
  EXPECT_LE(c.outliers, c.pixels / 200);
  EXPECT_GT(control.outliers, c.pixels / 20);
}

// A black plane of opacity 0.3 in front of an emitter of radiance 1: the camera sees 0.7 (the fraction of rays
// through), within 5 standard errors of the image mean.
TEST(OpacityScene, FractionalOpacityTransmitsTheRest) {
  const TestRender r = render_json(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 20,
                                                  "resolution": [24, 24]},
    "materials": {"black": {"type": "diffuse", "albedo": 0, "opacity": 0.3}},
    "shapes": [{"type": "quad", "material": "black", "vertices": [[-20, -20, 0], [20, -20, 0], [20, 20, 0], [-20, 20, 0]]},
               {"type": "quad", "emission": 1, "vertices": [[-20, -20, -1], [20, -20, -1], [20, 20, -1], [-20, 20, -1]]}]})",
                                   64, 0, 9);
  const ImageStats s = image_stats(r.film);
  fmt::print("opacity 0.3 in front of a light: {:.5f} +- {:.5f}\n", s.mean.g, s.standard_error.g);
  EXPECT_NEAR(s.mean.g, 0.7, 5.0 * s.standard_error.g);
}

}  // namespace
}  // namespace kozu::test
