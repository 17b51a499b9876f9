// Keys every surface material accepts: normal maps (materials/normal_map.h), the bend that keeps a perturbed
// normal facing the viewer (materials/shading_normal.h), and their parsing on every material type.
#include "support/render_test.h"

#include "core/rng.h"
#include "geometry/embree_scene.h"
#include "materials/bump_map.h"
#include "materials/normal_map.h"
#include "materials/shading_normal.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace kozu::test {
namespace {

// A hit on the unit quad z = 0 (uv = ((x + 1) / 2, (y + 1) / 2), front +z) seen from direction wo.
struct QuadHit {
  std::vector<std::unique_ptr<Shape>> shapes;
  std::unique_ptr<EmbreeScene> accel;
  SurfaceInteraction si;
  explicit QuadHit(const Vec3& wo = Vec3(0, 0, 1), const Vec2& at = Vec2(0.1f, -0.2f), bool mirrored = false) {
    std::vector<Vec2> uv = {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};
    if (mirrored)
      for (Vec2& x : uv) x.x = 1.0f - x.x;
    shapes.push_back(std::make_unique<TriangleMesh>(
        std::vector<Vec3>{Vec3(-1, -1, 0), Vec3(1, -1, 0), Vec3(1, 1, 0), Vec3(-1, 1, 0)},
        std::vector<uint32_t>{0, 1, 2, 0, 2, 3}, std::vector<Vec3>{}, uv));
    accel = std::make_unique<EmbreeScene>(shapes);
    const Vec3 p(at, 0.0f);
    EXPECT_TRUE(accel->intersect(Ray{p + 3.0f * wo, -wo, kInfinity}, si));
  }
};

// The texel that encodes the unit tangent-space normal m.
Rgb encode(const Vec3& m) { return 0.5f * (m + 1.0f); }

NormalMap constant_map(const Rgb& texel, float strength = 1.0f, bool flip_y = false) {
  return NormalMap(std::make_unique<ConstantTexture>(texel), strength, flip_y);
}

void expect_orthonormal(const Frame& f) {
  EXPECT_NEAR(glm::length(f.s), 1.0f, 1e-5f);
  EXPECT_NEAR(glm::length(f.t), 1.0f, 1e-5f);
  EXPECT_NEAR(glm::length(f.n), 1.0f, 1e-5f);
  EXPECT_NEAR(glm::dot(f.s, f.t), 0.0f, 1e-5f);
  EXPECT_NEAR(glm::dot(f.s, f.n), 0.0f, 1e-5f);
  EXPECT_NEAR(glm::length(glm::cross(f.s, f.t) - f.n), 0.0f, 1e-5f);  // right-handed
}

TEST(NormalMap, FlatTexelLeavesTheNormalUnchanged) {
  for (const bool mirrored : {false, true}) {
    QuadHit h(glm::normalize(Vec3(0.3f, -0.2f, 1.0f)), Vec2(0.1f, -0.2f), mirrored);
    const Vec3 n0 = h.si.shading.n;
    constant_map(Rgb(0.5f, 0.5f, 1.0f)).apply(h.si);
    EXPECT_NEAR(glm::length(h.si.shading.n - n0), 0.0f, 1e-6f);
    expect_orthonormal(h.si.shading);
    // The frame's first axis now follows the tangent (dp/du = ±x).
    EXPECT_NEAR(std::abs(h.si.shading.s.x), 1.0f, 1e-6f);
  }
}

// A texel tilted by angle a towards +X (the tangent) or +Y (the bitangent) turns the normal by a in that direction,
// in world space along dp/du or dp/dv, whatever the handedness of the mapping.
TEST(NormalMap, TiltedTexelRotatesTheNormalByItsAngle) {
  for (const bool mirrored : {false, true})
    for (const float deg : {5.0f, 20.0f, 45.0f, 70.0f}) {
      const float a = deg * kPi / 180.0f;
      for (int axis = 0; axis < 2; ++axis) {
        const Vec3 m = axis == 0 ? Vec3(std::sin(a), 0, std::cos(a)) : Vec3(0, std::sin(a), std::cos(a));
        QuadHit h(Vec3(0, 0, 1), Vec2(0.1f, -0.2f), mirrored);
        Vec3 dpdu, dpdv;
        h.si.shape->uv_derivatives(h.si, &dpdu, &dpdv);
        constant_map(encode(m)).apply(h.si);
        const Vec3& n = h.si.shading.n;
        EXPECT_NEAR(safe_acos(glm::dot(n, h.si.ng)), a, 2e-5f) << deg << " degrees, axis " << axis;
        const Vec3 towards = glm::normalize(axis == 0 ? dpdu : dpdv);
        EXPECT_NEAR(glm::dot(n, towards), std::sin(a), 2e-5f) << deg << " degrees, axis " << axis;
        expect_orthonormal(h.si.shading);
      }
    }
}

// Strength scales X and Y (glTF normalTexture.scale): tan of the tilt scales by it. DirectX maps negate Y.
TEST(NormalMap, StrengthAndDirectXConvention) {
  const float a = 30.0f * kPi / 180.0f;
  for (const float s : {0.0f, 0.5f, 2.0f}) {
    QuadHit h;
    constant_map(encode(Vec3(std::sin(a), 0, std::cos(a))), s).apply(h.si);
    EXPECT_NEAR(safe_acos(glm::dot(h.si.shading.n, h.si.ng)), std::atan(s * std::tan(a)), 2e-5f) << s;
  }
  QuadHit gl, dx;
  const Rgb texel = encode(Vec3(0, std::sin(a), std::cos(a)));
  constant_map(texel).apply(gl.si);
  constant_map(texel, 1.0f, true).apply(dx.si);
  EXPECT_NEAR(gl.si.shading.n.y, std::sin(a), 2e-5f);  // +Y = +v = +y on this quad
  EXPECT_NEAR(dx.si.shading.n.y, -std::sin(a), 2e-5f);
}

// A normal tilted away from a grazing viewer is bent until the viewer is above it, and stays on the geometric
// front side; seen from the back (two-sided materials) likewise on the back.
TEST(ShadingNormal, BentNormalsFaceTheViewer) {
  Pcg32 rng(11);
  int bent = 0;
  for (int i = 0; i < 2000; ++i) {
    const float side = i % 2 ? 1.0f : -1.0f;
    const Vec3 wo = glm::normalize(
        Vec3(2.0f * rng.next_float() - 1.0f, 2.0f * rng.next_float() - 1.0f, side * (0.01f + rng.next_float())));
    const Vec3 m =
        glm::normalize(Vec3(2.0f * rng.next_float() - 1.0f, 2.0f * rng.next_float() - 1.0f, 0.05f + rng.next_float()));
    QuadHit h(wo);
    constant_map(encode(m)).apply(h.si);
    const Vec3& n = h.si.shading.n;
    EXPECT_GT(glm::dot(n, h.si.ng), 0.0f);
    EXPECT_GT(glm::dot(h.si.wo, n) * side, 0.0f) << i;
    expect_orthonormal(h.si.shading);
    if (glm::dot(h.si.wo, Vec3(h.si.shading.n)) * side < 0.0101f) ++bent;
  }
  EXPECT_GT(bent, 50);  // the case arises (about a fifth of these draws)
}

TEST(ShadingNormal, BendKeepsNormalsThatAlreadyFaceTheViewer) {
  const Vec3 ng(0, 0, 1), n = glm::normalize(Vec3(0.3f, 0.1f, 1.0f));
  EXPECT_EQ(bend_shading_normal(n, glm::normalize(Vec3(-0.1f, 0.2f, 1.0f)), ng), n);
  const Vec3 b = bend_shading_normal(n, glm::normalize(Vec3(-1.0f, 0.0f, 0.05f)), ng);
  EXPECT_GT(glm::dot(b, glm::normalize(Vec3(-1.0f, 0.0f, 0.05f))), 0.0f);
}

// Every surface material type takes the common keys; misspellings and orphans are errors naming the path.
TEST(SurfaceMapsParse, EveryMaterialTakesNormalMaps) {
  for (const char* type : {R"("type": "diffuse")", R"("type": "conductor")", R"("type": "dielectric")",
                           R"("type": "plastic")", R"("type": "subsurface", "mfp": 0.1)"}) {
    const std::string json = fmt::format(R"({{"camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0]}},
      "materials": {{"m": {{{}, "normal_map": {{"type": "constant", "value": [0.6, 0.5, 0.9]}},
                           "normal_map_strength": 0.5, "normal_map_convention": "directx"}}}},
      "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}}]}})",
                                         type);
    std::unique_ptr<Scene> scene;
    try {
      scene = load_scene_text(json, "scene.json", ".");
    } catch (const std::exception& e) {
      ADD_FAILURE() << type << ": " << e.what();
      continue;
    }
    ASSERT_EQ(scene->materials.size(), 1u);
    EXPECT_TRUE(scene->materials[0]->perturbs_shading()) << type;
  }
}

std::string load_error(const std::string& material) {
  const std::string json = fmt::format(R"({{"camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0]}},
      "materials": {{"m": {}}},
      "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}}]}})",
                                       material);
  try {
    load_scene_text(json, "scene.json", ".");
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(SurfaceMapsParse, BadKeysAreErrors) {
  EXPECT_NE(load_error(R"({"type": "diffuse", "normal_map": 0.5, "normal_map_strenght": 1})")
                .find("/materials/m/normal_map_strenght"),
            std::string::npos);
  EXPECT_NE(load_error(R"({"type": "diffuse", "normal_map_strength": 1})").find("needs a 'normal_map'"),
            std::string::npos);
  EXPECT_NE(load_error(R"({"type": "diffuse", "normal_map": 0.5, "normal_map_strength": -1})")
                .find("/materials/m/normal_map_strength"),
            std::string::npos);
  EXPECT_NE(load_error(R"({"type": "diffuse", "normal_map": 0.5, "normal_map_convention": "d3d"})")
                .find("/materials/m/normal_map_convention"),
            std::string::npos);
  EXPECT_NE(load_error(R"({"type": "diffuse", "normal_map": [0.5, 1.5, 1]})").find("/materials/m/normal_map"),
            std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// Opacity cut-outs (materials/opacity_mask.h, the accelerator's filter).

// A quad [-1, 1]² at z = 0 with the given "opacity" value, and a large opaque floor at z = −1.
std::unique_ptr<Scene> opacity_scene(const std::string& opacity) {
  return load_scene_text(fmt::format(R"({{"camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0]}},
    "materials": {{"cut": {{"type": "diffuse", "opacity": {}}}, "floor": {{"type": "diffuse"}}}},
    "shapes": [{{"type": "quad", "material": "cut", "vertices": [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]}},
               {{"type": "quad", "material": "floor", "vertices": [[-9, -9, -1], [9, -9, -1], [9, 9, -1], [-9, 9, -1]]}}]}})",
                                     opacity),
                         "scene.json", ".");
}

// A checker of opacity 1 and 0 (4 × 4 cells; cell (i, j) is opaque where i + j is even): closest-hit and shadow
// queries find the quad exactly in its opaque cells, and the floor through the holes.
TEST(Opacity, CheckerCutOutHolesForEveryQuery) {
  auto scene = opacity_scene(R"({"type": "checker", "scale": [4, 4], "a": 1, "b": 0})");
  Pcg32 rng(21);
  int opaque = 0, holes = 0;
  for (int k = 0; k < 4000; ++k) {
    const float u = rng.next_float(), v = rng.next_float();
    const int i = static_cast<int>(4.0f * u), j = static_cast<int>(4.0f * v);
    const float fu = 4.0f * u - i, fv = 4.0f * v - j;
    if (std::min({fu, fv, 1.0f - fu, 1.0f - fv}) < 1e-3f) continue;  // not on a cell boundary
    const bool is_opaque = (i + j) % 2 == 0;
    const Vec3 p(2.0f * u - 1.0f, 2.0f * v - 1.0f, 0.0f);
    const Vec3 o = p + Vec3(0.3f, -0.2f, 2.0f);
    const Vec3 d = glm::normalize(p - o);
    SurfaceInteraction si;
    ASSERT_TRUE(scene->intersect(Ray{o, d, kInfinity}, si));
    EXPECT_NEAR(si.p.z, is_opaque ? 0.0f : -1.0f, 1e-4f) << u << ", " << v;
    // A shadow ray from above to a point on the floor below: blocked exactly by the opaque cells.
    const float t_floor = (-1.0f - o.z) / d.z;
    EXPECT_EQ(scene->occluded(Ray{o, d, 0.999f * t_floor}), is_opaque) << u << ", " << v;
    // And from below (the back side) likewise.
    const Vec3 below = o + 0.999f * t_floor * d;  // just above the floor
    EXPECT_EQ(scene->occluded(Ray{below, -d, 0.998f * t_floor}), is_opaque) << u << ", " << v;
    (is_opaque ? opaque : holes)++;
  }
  EXPECT_GT(opaque, 1500);
  EXPECT_GT(holes, 1500);
}

TEST(Opacity, ZeroIsInvisibleAndOneIsOpaque) {
  auto none = opacity_scene("0");
  auto full = opacity_scene("1");
  EXPECT_EQ(full->shapes[0]->opacity, nullptr);  // "opacity": 1 installs nothing
  for (float x : {-0.5f, 0.0f, 0.7f}) {
    SurfaceInteraction si;
    ASSERT_TRUE(none->intersect(Ray{Vec3(x, 0.1f, 3.0f), Vec3(0, 0, -1), kInfinity}, si));
    EXPECT_NEAR(si.p.z, -1.0f, 1e-5f);
    ASSERT_TRUE(full->intersect(Ray{Vec3(x, 0.1f, 3.0f), Vec3(0, 0, -1), kInfinity}, si));
    EXPECT_NEAR(si.p.z, 0.0f, 1e-5f);
    EXPECT_FALSE(none->occluded(Ray{Vec3(x, 0.1f, 3.0f), Vec3(0, 0, -1), 3.5f}));
    EXPECT_TRUE(full->occluded(Ray{Vec3(x, 0.1f, 3.0f), Vec3(0, 0, -1), 3.5f}));
  }
}

// Fractional opacity 0.3: of N random rays through the quad, the fraction stopped is 0.3 within 5 binomial
// standard errors sqrt(0.3 · 0.7 / N), for closest-hit and shadow queries alike; each ray's decision is the same
// for both queries and when traced again.
TEST(Opacity, FractionalOpacityStopsThatFractionOfRays) {
  auto scene = opacity_scene("0.3");
  Pcg32 rng(22);
  constexpr int kRays = 200000;
  int stopped = 0, occluded = 0, disagree = 0, unstable = 0;
  for (int k = 0; k < kRays; ++k) {
    const Vec3 p(1.9f * rng.next_float() - 0.95f, 1.9f * rng.next_float() - 0.95f, 0.0f);
    const Vec3 o = p + Vec3(2.0f * rng.next_float() - 1.0f, 2.0f * rng.next_float() - 1.0f, 1.0f + rng.next_float());
    const Vec3 d = glm::normalize(p - o);
    SurfaceInteraction si;
    const bool hit_quad = scene->intersect(Ray{o, d, kInfinity}, si) && si.p.z > -0.5f;
    const float t_floor = (-1.0f - o.z) / d.z;
    const bool blocked = scene->occluded(Ray{o, d, 0.999f * t_floor});
    stopped += hit_quad;
    occluded += blocked;
    disagree += hit_quad != blocked;
    SurfaceInteraction again;
    unstable += hit_quad != (scene->intersect(Ray{o, d, kInfinity}, again) && again.p.z > -0.5f);
  }
  const double se = std::sqrt(0.3 * 0.7 / kRays);
  fmt::print("opacity 0.3: stopped {:.4f}, occluded {:.4f} (+- {:.4f})\n", double(stopped) / kRays,
             double(occluded) / kRays, se);
  EXPECT_NEAR(double(stopped) / kRays, 0.3, 5.0 * se);
  EXPECT_NEAR(double(occluded) / kRays, 0.3, 5.0 * se);
  EXPECT_EQ(disagree, 0);
  EXPECT_EQ(unstable, 0);
}

TEST(SurfaceMapsParse, OpacityErrors) {
  EXPECT_NE(load_error(R"({"type": "diffuse", "opacity": 1.5})").find("/materials/m/opacity"), std::string::npos);
  EXPECT_NE(load_error(R"({"type": "diffuse", "opacity": {"type": "checker", "a": 2}})").find("/materials/m/opacity/a"),
            std::string::npos);
  // An emitter cannot have holes (its light would still be sampled there).
  const std::string json = R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
      "materials": {"m": {"type": "diffuse", "opacity": 0.5}},
      "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m", "emission": 1}]})";
  try {
    load_scene_text(json, "scene.json", ".");
    ADD_FAILURE() << "an emitter with an opacity cut-out was accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("/shapes/0/material"), std::string::npos) << e.what();
  }
}

// Opacity on a sphere: its holes follow the sphere's (u, v) (Sphere::hit_uv): u >= 0.5 is cut away.
TEST(Opacity, SphereHolesFollowItsUv) {
  auto scene = load_scene_text(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
    "materials": {"cut": {"type": "diffuse", "opacity": {"type": "checker", "scale": [2, 1], "a": 1, "b": 0}}},
    "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "cut"}]})",
                               "scene.json", ".");
  // u = phi / 2 pi with phi = atan2(-z, x): the +z side (u = 0.75) is cut, the −z side (u = 0.25) kept.
  SurfaceInteraction si;
  ASSERT_TRUE(scene->intersect(Ray{Vec3(0.1f, 0.2f, 5.0f), Vec3(0, 0, -1), kInfinity}, si));
  EXPECT_LT(si.p.z, 0.0f);  // through the hole at the front, onto the inside of the back
  // A shadow ray that ends inside the sphere passes the cut front unblocked.
  EXPECT_FALSE(scene->occluded(Ray{Vec3(0.1f, 0.2f, 5.0f), Vec3(0, 0, -1), 5.0f}));
  EXPECT_TRUE(scene->occluded(Ray{Vec3(0.1f, 0.2f, -5.0f), Vec3(0, 0, 1), 4.5f}));
}

// ---------------------------------------------------------------------------------------------
// Bump maps (materials/bump_map.h).

// h(u, v) = a u + b v + c: a linear ramp, whose central differences are exact.
class RampTexture final : public Texture {
 public:
  RampTexture(float a, float b, float c) : a_(a), b_(b), c_(c) {}
  Rgb eval(const TextureQuery& q) const override { return Rgb(a_ * q.uv.x + b_ * q.uv.y + c_); }

 private:
  float a_, b_, c_;
};

// On the quad [-1, 1]² (u = (x + 1) / 2, v = (y + 1) / 2; mirrored: u = (1 − x) / 2) the height s (a u + b v) is
// the height field z = s (a (x + 1) / 2 + b (y + 1) / 2) (mirrored: s (a (1 − x) / 2 + ...)), whose normal is
// normalize(−dz/dx, −dz/dy, 1).
TEST(BumpMap, LinearRampGivesTheAnalyticTiltedNormal) {
  for (const bool mirrored : {false, true})
    for (const Vec2 ab : {Vec2(1, 0), Vec2(0, 1), Vec2(0.7f, -1.3f)})
      for (const float scale : {0.1f, 1.0f, -2.5f}) {
        QuadHit h(glm::normalize(Vec3(0.2f, 0.1f, 1.0f)), Vec2(0.1f, -0.2f), mirrored);
        BumpMap(std::make_unique<RampTexture>(ab.x, ab.y, 0.3f), scale).apply(h.si);
        const float dzdx = scale * ab.x * (mirrored ? -0.5f : 0.5f), dzdy = scale * ab.y * 0.5f;
        const Vec3 expected = glm::normalize(Vec3(-dzdx, -dzdy, 1.0f));
        // Tolerance: float rounding of the central difference, about ulp(h) / Δ = 6e-8 / 5e-4 relative to the slope.
        EXPECT_NEAR(glm::length(h.si.shading.n - expected), 0.0f, 2e-4f)
            << "mirrored " << mirrored << " a " << ab.x << " b " << ab.y << " scale " << scale;
        expect_orthonormal(h.si.shading);
      }
}

// A constant height changes nothing; on a sphere a ramp in v tilts the normal along dp/dv (towards the +y pole
// for a height decreasing towards it).
TEST(BumpMap, ConstantHeightIsFlatAndSphereRampTiltsAlongV) {
  QuadHit h(glm::normalize(Vec3(0.2f, 0.1f, 1.0f)));
  const Vec3 n0 = h.si.shading.n;
  BumpMap(std::make_unique<ConstantTexture>(Rgb(0.4f)), 3.0f).apply(h.si);
  EXPECT_NEAR(glm::length(h.si.shading.n - n0), 0.0f, 1e-6f);

  std::vector<std::unique_ptr<Shape>> shapes;
  shapes.push_back(std::make_unique<Sphere>(Vec3(0.0f), 1.0f));
  EmbreeScene accel(shapes);
  SurfaceInteraction si;
  ASSERT_TRUE(accel.intersect(Ray{Vec3(0.0f, 0.0f, 4.0f), Vec3(0, 0, -1), kInfinity}, si));  // equator, n = +z
  // h = −s v: dp/dv = pi r (+y) at the equator, so dh/dv = −s and the normal is normalize(pi r n + s dp/dv / |..|):
  // n' ∝ (0, s, pi).
  const float s = 0.8f;
  BumpMap(std::make_unique<RampTexture>(0.0f, -s, 0.0f), 1.0f).apply(si);
  EXPECT_NEAR(glm::length(si.shading.n - glm::normalize(Vec3(0.0f, s, kPi))), 0.0f, 1e-4f);
}

TEST(SurfaceMapsParse, BumpMapKeys) {
  EXPECT_EQ(load_error(R"({"type": "plastic", "bump_map": {"type": "checker"}, "bump_scale": 0.01})"), "");
  EXPECT_NE(load_error(R"({"type": "diffuse", "bump_scale": 1})").find("needs a 'bump_map'"), std::string::npos);
  EXPECT_NE(load_error(R"({"type": "diffuse", "normal_map": 0.5, "bump_map": 0.5})").find("not both"),
            std::string::npos);
}

}  // namespace
}  // namespace kozu::test
