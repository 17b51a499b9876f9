// The light hierarchy (lights/light_tree.h): its choices follow its own pmf (chi-square), every light that can
// light a point keeps a positive probability there (the condition for unbiased estimates), merged orientation cones
// hold their parts, and a render with many lights keeps its mean whichever selection it uses.
#include "support/chi2.h"
#include "support/render_test.h"

#include "core/rng.h"
#include "lights/light_tree.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace kozu::test {
namespace {

// Many lights of every kind: quads facing several ways (one two-sided), emissive meshes (one light per triangle; two
// of them quads, whose two triangles share a box and a cone, so that their node's choice is a constant),
// a sphere, point and spot lights, an environment and a distant light with a diameter.
std::unique_ptr<Scene> many_lights_scene() {
  std::string shapes;
  Pcg32 rng(11);
  for (int i = 0; i < 12; ++i) {
    const float x = 8.0f * rng.next_float() - 4.0f, y = 3.0f * rng.next_float() + 0.5f, z = 8.0f * rng.next_float() - 4.0f;
    const float s = 0.1f + 0.4f * rng.next_float();
    // Faces down, up, or sideways.
    const char* corners[3] = {"[[{0},{1},{2}],[{3},{1},{2}],[{3},{1},{4}],[{0},{1},{4}]]",
                              "[[{0},{1},{2}],[{0},{1},{4}],[{3},{1},{4}],[{3},{1},{2}]]",
                              "[[{0},{1},{2}],[{0},{5},{2}],[{0},{5},{4}],[{0},{1},{4}]]"};
    shapes += fmt::format(R"({{"type": "quad", "emission": {}, "two_sided": {}, "vertices": )", 1.0f + 9.0f * rng.next_float(),
                          i == 3 ? "true" : "false");
    shapes += fmt::format(fmt::runtime(corners[i % 3]), x, y, z, x + s, z + s, y + s);
    shapes += "},\n";
  }
  shapes += R"({"type": "mesh", "emission": 4, "positions": [[-1, 2, -1], [1, 2, -1], [0, 3, 0], [0, 2, 1]],
                "indices": [0, 1, 2, 1, 3, 2, 3, 0, 2, 0, 3, 1]},
               {"type": "mesh", "emission": 6, "positions": [[1, 3.5, 1], [2, 3.5, 1], [2, 3.5, 2], [1, 3.5, 2]],
                "indices": [0, 1, 2, 0, 2, 3]},
               {"type": "mesh", "emission": 2, "positions": [[-3, 0.5, -3], [-3, 1.5, -3], [-3, 1.5, -2], [-3, 0.5, -2]],
                "indices": [0, 1, 2, 0, 2, 3]},
               {"type": "sphere", "center": [2, 1, -2], "radius": 0.3, "emission": 5})";
  return load_scene_text(fmt::format(R"({{"camera": {{"position": [0, 1, -8], "look_at": [0, 1, 0]}},
    "shapes": [{}],
    "lights": [{{"type": "point", "position": [-3, 1, 2], "intensity": 3}},
               {{"type": "spot", "position": [0, 4, 0], "look_at": [1, 0, 0], "intensity": 20, "cone_angle": 25,
                 "falloff_angle": 15}},
               {{"type": "environment", "radiance": [0.2, 0.3, 0.4]}},
               {{"type": "directional", "direction": [1, -2, 0.5], "irradiance": 2, "angular_diameter": 5}}]}})",
                                     shapes),
                         "scene.json", ".");
}

Vec3 random_direction(Pcg32& rng) {
  const float z = 2.0f * rng.next_float() - 1.0f, phi = kTwoPi * rng.next_float();
  const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
  return Vec3(r * std::cos(phi), r * std::sin(phi), z);
}

// Shading points in and around the lights: in a medium (no normal) and on surfaces facing every way.
std::vector<LightSampleContext> contexts(int n, uint64_t seed) {
  std::vector<LightSampleContext> out;
  Pcg32 rng(seed);
  for (int i = 0; i < n; ++i) {
    const Vec3 p(10.0f * rng.next_float() - 5.0f, 5.0f * rng.next_float() - 0.5f, 10.0f * rng.next_float() - 5.0f);
    out.push_back(LightSampleContext{p, i % 3 != 0 ? random_direction(rng) : Vec3(0.0f)});
  }
  return out;
}

TEST(LightTree, ChoicesFollowItsPmf) {
  const auto scene = many_lights_scene();
  const LightTree& tree = scene->light_tree();
  const size_t n = scene->lights.size();
  ASSERT_GT(n, 20u);
  ASSERT_GT(tree.node_count(), 10u);
  Chi2Options opt;
  opt.test_count = 8;
  for (const LightSampleContext& ctx : contexts(8, 5)) {
    // One more cell for "no light": it must hold what the pmfs leave.
    std::vector<double> observed(n + 1, 0.0), expected(n + 1, 0.0);
    double total = 0.0;
    for (size_t i = 0; i < n; ++i) total += expected[i] = tree.pmf(ctx, scene->lights[i].get());
    EXPECT_LE(total, 1.0 + 1e-5);
    expected[n] = std::max(0.0, 1.0 - total);
    constexpr int kN = 400000;
    Pcg32 rng(17);
    for (int s = 0; s < kN; ++s) {
      float pmf = 0.0f;
      const Light* l = tree.sample(ctx, rng.next_float(), &pmf);
      if (!l) {
        observed[n] += 1;
        continue;
      }
      observed[l->index] += 1;
      // The probability reported with a choice is the one pmf() gives for it.
      if (s < 2000) {
        EXPECT_NEAR(pmf, tree.pmf(ctx, l), 1e-5f * std::max(1.0f, pmf)) << l->index;
      }
    }
    for (double& e : expected) e *= kN;
    const Chi2Result r = chi2_test_counts(observed, expected, opt);
    EXPECT_TRUE(r.passed) << r.message;
  }
}

// The two triangles of an emissive mesh quad have the same bounds: their node chooses between them by power alone,
// without evaluating importances, and both keep the same probability everywhere (here equal powers), behind the
// quad too. ChoicesFollowItsPmf checks that those choices follow pmf() in the same scene.
TEST(LightTree, TrianglesOfAQuadAreChosenByPowerAlone) {
  const auto scene = many_lights_scene();
  const LightTree& tree = scene->light_tree();
  std::vector<const Light*> pair;
  for (const auto& l : scene->lights) {
    Vec3 c(0.0f);  // a triangle's centroid: the quad at y = 3.5 has the only ones there
    if (l->aim_point(&c) && std::abs(c.y - 3.5f) < 1e-4f) pair.push_back(l.get());
  }
  ASSERT_EQ(pair.size(), 2u);
  int positive = 0;
  for (const LightSampleContext& ctx : contexts(200, 9)) {
    const float a = tree.pmf(ctx, pair[0]), b = tree.pmf(ctx, pair[1]);
    EXPECT_EQ(a, b);
    positive += a > 0.0f;
  }
  EXPECT_GT(positive, 50);
}

// A light that can send radiance to the point must be choosable there: a probability of 0 would drop its light.
TEST(LightTree, EveryLightThatReachesAPointCanBeChosen) {
  const auto scene = many_lights_scene();
  const LightTree& tree = scene->light_tree();
  int reached = 0, checked = 0;
  Pcg32 rng(23);
  for (const LightSampleContext& ctx : contexts(400, 9)) {
    for (const auto& light : scene->lights) {
      bool reaches = false;
      for (int s = 0; s < 32 && !reaches; ++s) {
        const LightSample ls = light->sample(ctx, Vec2(rng.next_float(), rng.next_float()));
        reaches = ls.valid() && max_component(ls.radiance) > 0.0f;
      }
      if (!reaches) continue;
      ++reached;
      ++checked;
      EXPECT_GT(tree.pmf(ctx, light.get()), 0.0f)
          << "light " << light->index << " at (" << ctx.p.x << ", " << ctx.p.y << ", " << ctx.p.z << ") n ("
          << ctx.n.x << ", " << ctx.n.y << ", " << ctx.n.z << ")";
    }
  }
  EXPECT_GT(reached, 1000);
  EXPECT_GT(checked, 0);
}

// The importance prefers the nearer and the facing light: what makes the tree worth its traversal.
TEST(LightTree, ImportanceFavoursNearAndFacingLights) {
  auto scene = load_scene_text(R"({"camera": {"position": [0, 0, -5], "look_at": [0, 0, 0]},
    "shapes": [{"type": "quad", "emission": 1, "vertices": [[-0.1, 1, -0.1], [0.1, 1, -0.1], [0.1, 1, 0.1], [-0.1, 1, 0.1]]},
               {"type": "quad", "emission": 1, "vertices": [[9.9, 1, -0.1], [10.1, 1, -0.1], [10.1, 1, 0.1], [9.9, 1, 0.1]]}]})",
                               "scene.json", ".");
  const LightTree& tree = scene->light_tree();
  const Light* near = scene->lights[0].get();
  const Light* far = scene->lights[1].get();
  // Below the first light, which faces down or up depending on its winding: whichever side emits, the far one is
  // 10 units away and must be much less likely.
  const LightSampleContext below{Vec3(0, 0, 0), Vec3(0, 1, 0)};
  const LightSampleContext above{Vec3(0, 2, 0), Vec3(0, -1, 0)};
  const LightSampleContext& lit = near->bounds().cone.axis.y < 0.0f ? below : above;
  EXPECT_GT(tree.pmf(lit, near), 0.95f);
  EXPECT_NEAR(tree.pmf(lit, near) + tree.pmf(lit, far), 1.0f, 1e-5f);
  // Behind both one-sided lights' planes nothing reaches: no choice.
  const LightSampleContext& dark = &lit == &below ? above : below;
  float pmf = 1.0f;
  EXPECT_EQ(tree.sample(dark, 0.5f, &pmf), nullptr);
  EXPECT_EQ(pmf, 0.0f);
}

// Eq. (3) with the angles themselves, as the paper writes it: the reference for the cluster's cosine arithmetic.
double importance_by_angles(const LightBounds& b, const Vec3& p, const Vec3& n) {
  const Vec3 c = b.centre();
  const double dist2 = glm::dot(p - c, p - c), r2 = 0.25 * glm::dot(b.hi - b.lo, b.hi - b.lo);
  if (dist2 <= r2) return b.phi / std::max(r2, 1e-12);
  const double theta_u = std::asin(std::sqrt(r2 / dist2));
  const Vec3 w = glm::normalize(p - c);
  const double theta = std::acos(std::clamp<double>(glm::dot(b.cone.axis, w), -1.0, 1.0));
  const double theta_p = std::max(0.0, theta - b.cone.theta_o - theta_u);
  if (theta_p > b.cone.theta_e + 1e-3) return 0.0;
  double receiver = 1.0;
  if (glm::dot(n, n) > 0.0f)
    receiver = std::cos(std::max(0.0, std::acos(std::min(1.0, std::abs(double(glm::dot(n, w))))) - theta_u));
  return b.phi * std::max(std::cos(theta_p), 1e-3) * receiver / dist2;
}

TEST(LightCluster, ImportanceIsEquationThree) {
  Pcg32 rng(41);
  const auto direction = [&] { return random_direction(rng); };
  int zero = 0, positive = 0;
  for (int i = 0; i < 20000; ++i) {
    LightBounds b;
    b.lo = Vec3(rng.next_float(), rng.next_float(), rng.next_float()) * 2.0f - 1.0f;
    b.hi = b.lo + (i % 5 == 0 ? Vec3(0.0f) : Vec3(rng.next_float(), rng.next_float(), rng.next_float()) * 0.5f);
    b.cone = DirectionCone{direction(), (i % 3 == 0 ? 0.0f : kPi * rng.next_float()), 0.5f * kPi * rng.next_float()};
    b.phi = 0.5f + rng.next_float();
    const Vec3 p = direction() * (0.2f + 5.0f * rng.next_float());
    const Vec3 n = i % 4 == 0 ? Vec3(0.0f) : direction();
    const double expected = importance_by_angles(b, p, n);
    const double got = LightCluster::from(b).importance(p, n);
    EXPECT_NEAR(got, expected, 2e-3 * expected + 1e-6) << i;
    (expected > 0.0 ? positive : zero) += 1;
  }
  EXPECT_GT(zero, 1000);
  EXPECT_GT(positive, 1000);
}

TEST(LightBounds, MergedConesHoldBothCones) {
  Pcg32 rng(31);
  const auto direction = [&] { return random_direction(rng); };
  for (int i = 0; i < 10000; ++i) {
    const DirectionCone a{direction(), kPi * rng.next_float() * (i % 4 == 0 ? 0.05f : 1.0f), 0.5f * kPi * rng.next_float()};
    const DirectionCone b{direction(), kPi * rng.next_float() * (i % 5 == 0 ? 0.05f : 1.0f), 0.5f * kPi * rng.next_float()};
    const DirectionCone m = DirectionCone::merge(a, b);
    for (const DirectionCone* c : {&a, &b}) {
      // Every direction within θo of c's axis lies within θo of m's (all of them once that reaches π).
      EXPECT_LE(std::min(safe_acos(glm::dot(m.axis, c->axis)) + c->theta_o, kPi), m.theta_o + 2e-3f) << i;
      EXPECT_GE(m.theta_e, c->theta_e) << i;
    }
    EXPECT_LE(m.theta_o, kPi);
  }
}

// With many lights the image's mean is the same whichever way lights are chosen: the tree's pmfs enter both the
// next-event estimates and the MIS weights of emission met by BSDF rays, and a mismatch between them would bias it.
TEST(LightTree, RenderKeepsItsMeanUnderEitherSelection) {
  std::string lights;
  // Lights of very different powers spread along the floor, near it: the tree and selection by power give them very
  // different probabilities at most points, and BSDF rays meet them often.
  for (int i = 0; i < 16; ++i) {
    const float x = -4.0f + 0.5f * i, y = 0.4f + 0.2f * (i % 3);
    lights += fmt::format(R"({{"type": "quad", "emission": {}, "vertices": [[{},{},-0.2],[{},{},-0.2],[{},{},0.2],[{},{},0.2]]}},)",
                          i % 4 == 0 ? 40 : 1, x, y, x + 0.4f, y, x + 0.4f, y, x, y);
  }
  const std::string scene = fmt::format(R"({{"camera": {{"position": [0, 3, -6], "look_at": [0, 0, 0], "resolution": [24, 16]}},
    "render": {{"light_selection": "@MODE@", "max_depth": 3, "filter": "box"}},
    "materials": {{"floor": {{"type": "diffuse", "albedo": 0.6}}, "gloss": {{"type": "conductor", "roughness": 0.3}}}},
    "shapes": [{} {{"type": "quad", "material": "floor", "vertices": [[-6, 0, -6], [-6, 0, 6], [6, 0, 6], [6, 0, -6]]}},
               {{"type": "sphere", "material": "gloss", "center": [0.5, 0.6, 0], "radius": 0.6}}],
    "lights": [{{"type": "point", "position": [2, 2, -1], "intensity": 2}},
               {{"type": "environment", "radiance": 0.1}}]}})",
                                         lights);
  ImageStats s[2];
  const char* modes[2] = {"tree", "power"};
  for (int m = 0; m < 2; ++m) {
    std::string text = scene;
    text.replace(text.find("@MODE@"), 6, modes[m]);
    const TestRender r = render_json(text, 256, 0, 7);
    s[m] = image_stats(r.film);
  }
  for (int c = 0; c < 3; ++c) {
    const double diff = s[0].mean[c] - s[1].mean[c];
    const double se = std::hypot(s[0].standard_error[c], s[1].standard_error[c]);
    EXPECT_LT(std::abs(diff), 4.0 * se) << "channel " << c << ": tree " << s[0].mean[c] << ", power " << s[1].mean[c];
    // The tree is there for its variance: it must not be worse on a scene of many lights.
    EXPECT_LT(s[0].standard_error[c], s[1].standard_error[c]) << "channel " << c;
  }
}

}  // namespace
}  // namespace kozu::test
