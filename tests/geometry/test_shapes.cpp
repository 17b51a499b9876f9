// Shapes and the Embree scene: hit reconstruction, orientation and robust ray offsets.
#include "support/render_test.h"

#include "core/rng.h"
#include "core/warp.h"
#include "geometry/polygon.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace kozu::test {
namespace {

std::unique_ptr<Scene> sphere_scene() {
  return load_scene_text(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
    "materials": {"m": {"type": "diffuse"}},
    "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}]})",
                         "scene.json", ".");
}

// Rays that pass within 1e-9 .. 1e-5 of tangency: Embree's float root is ill-conditioned there,
// yet every reported hit must face the ray (entry from outside), or a two-sided BSDF would
// scatter into the sphere.
TEST(Sphere, GrazingHitsFaceTheRay) {
  auto scene = sphere_scene();
  Pcg32 rng(3);
  int hits = 0, wrong = 0;
  for (float dist : {4.0f, 40.0f}) {
    const Vec3 o(0.0f, 0.0f, dist);
    for (int i = 0; i < 200000; ++i) {
      // A tangent point direction around the limb, pulled inwards by delta.
      const float phi = kTwoPi * rng.next_float();
      const float delta = std::pow(10.0f, -9.0f + 4.0f * rng.next_float());
      const float b = 1.0f - delta;  // distance of the ray line from the centre
      // Direction from o to the point at distance b from the axis, in the tangent plane.
      const float tan_a = b / std::sqrt(dist * dist - b * b);
      const Vec3 d = glm::normalize(Vec3(tan_a * std::cos(phi), tan_a * std::sin(phi), -1.0f));
      SurfaceInteraction si;
      if (!scene->intersect(Ray{o, d, kInfinity}, si)) continue;
      ++hits;
      if (!(glm::dot(si.wo, si.ng) > 0.0f) || !si.front_face) ++wrong;
    }
  }
  EXPECT_GT(hits, 1000);
  EXPECT_EQ(wrong, 0) << "of " << hits << " grazing hits";
}

// Rays leaving a surface through the robust offset never re-hit it: reflections off the outside
// of a sphere and refractions into it, from many points and directions.
// Rays spawned from sphere hits, outwards and inwards, for spheres from radius 1 at the origin to radius 10^4
// far from it (a ground sphere's top sits near the origin while its centre is 10^4 away: the intersection's
// error grows with |centre| + radius, and SurfaceInteraction::p_error must cover it).
TEST(Sphere, SpawnedRaysDoNotSelfIntersect) {
  struct Case {
    Vec3 center;
    float radius;
  };
  for (const Case& c : {Case{Vec3(0.0f), 1.0f}, Case{Vec3(0, -1e3f, 0), 1e3f}, Case{Vec3(0, -1e4f, 0), 1e4f},
                        Case{Vec3(3e4f, -1e4f, 2e4f), 1e4f}}) {
    auto scene = load_scene_text(fmt::format(R"({{"camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0]}},
      "materials": {{"m": {{"type": "diffuse"}}}},
      "shapes": [{{"type": "sphere", "center": [{}, {}, {}], "radius": {}, "material": "m"}}]}})",
                                             c.center.x, c.center.y, c.center.z, c.radius),
                                 "scene.json", ".");
    Pcg32 rng(5);
    int self_hits = 0, inside_misses = 0;
    for (int i = 0; i < 100000; ++i) {
      const Vec3 o =
          c.center + 3.0f * c.radius * warp::square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
      const Vec3 target =
          c.center + 0.9f * c.radius * warp::square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
      SurfaceInteraction si;
      if (!scene->intersect(Ray{o, glm::normalize(target - o), kInfinity}, si)) continue;
      const Frame f(si.ng);
      // Outward: reflect into the upper hemisphere; must escape.
      const Vec3 out = f.to_world(warp::square_to_uniform_hemisphere(Vec2(rng.next_float(), rng.next_float())));
      SurfaceInteraction s2;
      if (scene->intersect(si.spawn_ray(out), s2)) ++self_hits;
      // Inward: must hit the far side from inside, at a positive distance.
      const Vec3 in = -f.to_world(warp::square_to_uniform_hemisphere(Vec2(rng.next_float(), rng.next_float())));
      if (!scene->intersect(si.spawn_ray(in), s2) || s2.front_face) ++inside_misses;
    }
    EXPECT_EQ(self_hits, 0) << "radius " << c.radius;
    EXPECT_EQ(inside_misses, 0) << "radius " << c.radius;
  }
}

// A ray Embree would reject (NaN or beyond ±1.8e18) aborted the process inside Embree's assertion; it now hits
// nothing, and a shadow ray counts as blocked.
TEST(EmbreeScene, InvalidRaysHitNothing) {
  auto scene = sphere_scene();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const Ray& r : {Ray{Vec3(nan, 0, 5), Vec3(0, 0, -1), kInfinity}, Ray{Vec3(0, 0, 5), Vec3(0, nan, -1), kInfinity},
                       Ray{Vec3(0, 0, 1e30f), Vec3(0, 0, -1), kInfinity}, Ray{Vec3(0, 0, 5), Vec3(0, 0, -1), nan}}) {
    SurfaceInteraction si;
    EXPECT_FALSE(scene->intersect(r, si));
    EXPECT_TRUE(scene->occluded(r));
  }
  SurfaceInteraction si;
  EXPECT_TRUE(scene->intersect(Ray{Vec3(0, 0, 5), Vec3(0, 0, -1), kInfinity}, si));  // a valid ray still hits
}

// open_edges: a cube whose faces have their own vertices (24, as exporters split them at UV seams) is closed; a
// missing face opens its 4 edges; a quad has 4; a sphere none.
TEST(TriangleMesh, OpenEdgesMatchVerticesByPosition) {
  std::vector<Vec3> p;
  std::vector<uint32_t> idx;
  for (int axis = 0; axis < 3; ++axis)
    for (const float side : {-1.0f, 1.0f}) {
      const auto base = static_cast<uint32_t>(p.size());
      for (const auto& [a, b] : {std::pair{-1.0f, -1.0f}, {1.0f, -1.0f}, {1.0f, 1.0f}, {-1.0f, 1.0f}}) {
        Vec3 v(0.0f);
        v[axis] = side;
        v[(axis + 1) % 3] = a;
        v[(axis + 2) % 3] = b;
        p.push_back(v);
      }
      idx.insert(idx.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    }
  EXPECT_EQ(TriangleMesh(p, idx).open_edges(), 0u);
  std::vector<uint32_t> five(idx.begin(), idx.end() - 6);
  EXPECT_EQ(TriangleMesh(p, five).open_edges(), 4u);
  EXPECT_EQ(TriangleMesh({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)}, {0, 1, 2, 0, 2, 3}).open_edges(),
            4u);
  EXPECT_EQ(Sphere(Vec3(0.0f), 1.0f).open_edges(), 0u);
}

TEST(TriangleMesh, HitReconstructionAndOrientation) {
  auto scene = load_scene_text(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
    "materials": {"m": {"type": "diffuse"}},
    "shapes": [{"type": "mesh", "material": "m", "positions": [[-1, -1, 0], [1, -1, 0], [0, 1, 0]], "indices": [0, 1, 2],
                "normals": [[0, 0, 1], [0, 0, 1], [0, 0, -1]]}]})",
                               "scene.json", ".");
  SurfaceInteraction si;
  ASSERT_TRUE(scene->intersect(Ray{Vec3(0.0f, 0.0f, 3.0f), Vec3(0, 0, -1), kInfinity}, si));
  EXPECT_NEAR(si.t, 3.0f, 1e-6f);
  EXPECT_NEAR(glm::length(si.p), 0.0f, 1e-6f);
  EXPECT_EQ(si.ng, Vec3(0, 0, 1));  // counter-clockwise seen from +z
  EXPECT_TRUE(si.front_face);
  // The interpolated shading normal is flipped to the geometric front side when needed.
  EXPECT_GT(glm::dot(si.shading.n, si.ng), 0.0f);
  ASSERT_TRUE(scene->intersect(Ray{Vec3(0.0f, 0.0f, -3.0f), Vec3(0, 0, 1), kInfinity}, si));
  EXPECT_FALSE(si.front_face);
}

// ---- polygons: judged the same at every scale --------------------------------------------------------------

// An outline in 2D coordinates, scaled by `scale`, in the plane through `offset` spanned by e0, e1.
std::vector<Vec3> placed(const std::vector<Vec2>& outline, double scale, const Vec3& offset, const Vec3& e0,
                         const Vec3& e1) {
  std::vector<Vec3> v;
  for (const Vec2& p : outline) v.push_back(offset + float(scale) * (p.x * e0 + p.y * e1));
  return v;
}

// Twice the area of the triangles, to compare with the outline's.
double triangulated_area(const std::vector<Vec3>& v, const std::vector<uint32_t>& idx) {
  double a = 0.0;
  for (size_t i = 0; i < idx.size(); i += 3) {
    const glm::dvec3 p0(v[idx[i]]), p1(v[idx[i + 1]]), p2(v[idx[i + 2]]);
    a += glm::length(glm::cross(p1 - p0, p2 - p0)) / 2.0;
  }
  return a;
}

// A square 2·10^10 wide was refused as "self-intersecting": its squared lengths overflowed float, the normal became
// zero and every edge seemed to touch every other. Valid outlines are accepted, and self-crossing ones refused, at
// every scale the scene allows (coordinates up to kMaxCoordinate), in every orientation and away from the origin.
TEST(Polygon, SelfCrossingTestIsScaleInvariant) {
  const std::vector<Vec2> square = {{-0.5f, -0.5f}, {0.5f, -0.5f}, {0.5f, 0.5f}, {-0.5f, 0.5f}};
  const std::vector<Vec2> l_shape = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};  // non-convex
  const std::vector<Vec2> bowtie = {{0, 0}, {2, 2}, {2, 0}, {0, 1}};  // lobes of unequal area: not zero
  const std::vector<Vec2> pentagram = {
      {0, 1}, {0.588f, -0.809f}, {-0.951f, 0.309f}, {0.951f, 0.309f}, {-0.588f, -0.809f}};
  // A vertex on a non-neighbouring edge: the outline touches itself.
  const std::vector<Vec2> touching = {{0, 0}, {2, 0}, {2, 2}, {1, 0}, {0, 2}};
  const Vec3 x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
  const Vec3 tilted0 = glm::normalize(Vec3(1, 2, 3)), tilted1 = glm::normalize(glm::cross(tilted0, Vec3(0, 0, 1)));
  const std::vector<std::pair<Vec3, Vec3>> planes = {{x, y}, {x, z}, {z, x}, {y, z}, {tilted0, tilted1}};
  for (const double scale : {1e-6, 1.0, 2e10, 1e14}) {
    for (const auto& [e0, e1] : planes) {
      for (const Vec3 offset : {Vec3(0.0f), Vec3(float(3 * scale), float(-scale), float(0.5 * scale))}) {
        const std::string where = fmt::format("scale {:g}, plane ({:g},{:g},{:g})-({:g},{:g},{:g}), offset {:g}", scale,
                                              e0.x, e0.y, e0.z, e1.x, e1.y, e1.z, offset.x);
        for (const auto* valid : {&square, &l_shape}) {
          const std::vector<Vec3> v = placed(*valid, scale, offset, e0, e1);
          std::vector<uint32_t> idx;
          ASSERT_NO_THROW(idx = triangulate_polygon(v)) << where;
          ASSERT_EQ(idx.size(), 3 * (v.size() - 2)) << where;
          const double area = valid == &square ? 1.0 : 3.0;
          EXPECT_NEAR(triangulated_area(v, idx) / (scale * scale), area, 1e-3 * area) << where;
        }
        for (const auto* crossing : {&bowtie, &pentagram, &touching}) {
          try {
            triangulate_polygon(placed(*crossing, scale, offset, e0, e1));
            ADD_FAILURE() << "accepted a self-crossing outline at " << where;
          } catch (const PolygonError& e) {
            EXPECT_NE(std::string(e.what()).find("self-intersecting"), std::string::npos) << e.what() << ", " << where;
          }
        }
      }
    }
  }
}

// The same square through the scene loader, as a user gives it: it loads and a ray hits it with finite uv.
TEST(Polygon, HugeSquareLoadsWithFiniteUv) {
  auto scene = load_scene_text(R"({"camera": {"position": [0, 0, 5e10], "look_at": [0, 0, 0]},
    "materials": {"m": {"type": "diffuse"}},
    "shapes": [{"type": "polygon", "material": "m",
                "vertices": [[-1e10, -1e10, 0], [1e10, -1e10, 0], [1e10, 1e10, 0], [-1e10, 1e10, 0]]}]})",
                               "scene.json", ".");
  SurfaceInteraction si;
  ASSERT_TRUE(scene->intersect(Ray{Vec3(5e9f, -5e9f, 3e10f), Vec3(0, 0, -1), kInfinity}, si));
  EXPECT_TRUE(std::isfinite(si.uv.x) && std::isfinite(si.uv.y)) << si.uv.x << ", " << si.uv.y;
  EXPECT_TRUE(si.front_face);
}

}  // namespace
}  // namespace kozu::test
