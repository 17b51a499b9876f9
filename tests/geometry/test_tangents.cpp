// Tangent frames for normal maps (Shape::tangent, geometry/mesh_tangents.h): on every shape the tangent follows
// dp/du, the bitangent b = w · cross(n, t) follows dp/dv, and w = −1 exactly where the (u, v) mapping is mirrored.
#include "core/rng.h"
#include "core/transform.h"
#include "geometry/embree_scene.h"
#include "geometry/mesh_cleanup.h"
#include "geometry/mesh_tangents.h"
#include "geometry/shape.h"
#include "geometry/shape_registry.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <memory>
#include <vector>

namespace kozu::test {
namespace {

// Intersects a single shape with rays from above (or from `origin_at` for spheres) and checks the tangent
// convention at every hit; returns the number of hits checked.
struct Check {
  int hits = 0;
  int positive_w = 0, negative_w = 0;
};

Check check_tangents(std::unique_ptr<Shape> shape, const std::vector<Ray>& rays, float expected_w) {
  std::vector<std::unique_ptr<Shape>> shapes;
  shapes.push_back(std::move(shape));
  shapes[0]->prepare_tangents();
  EmbreeScene accel(shapes);
  Check c;
  for (const Ray& r : rays) {
    SurfaceInteraction si;
    if (!accel.intersect(r, si)) continue;
    ++c.hits;
    const Vec4 tw = si.shape->tangent(si);
    const Vec3 t(tw), n = si.shading.n;
    Vec3 dpdu, dpdv;
    si.shape->uv_derivatives(si, &dpdu, &dpdv);
    EXPECT_NEAR(glm::length(t), 1.0f, 1e-5f);
    EXPECT_NEAR(glm::dot(t, n), 0.0f, 1e-5f);
    // t ∝ dp/du (in the shading plane), b · dp/dv > 0, w as expected.
    const Vec3 du = glm::normalize(dpdu - glm::dot(dpdu, n) * n);
    EXPECT_GT(glm::dot(t, du), 0.999f) << fmt::format("t ({}, {}, {})", t.x, t.y, t.z);
    const Vec3 b = tw.w * glm::cross(n, t);
    EXPECT_GT(glm::dot(b, dpdv), 0.0f);
    EXPECT_EQ(tw.w, expected_w);
    (tw.w > 0 ? c.positive_w : c.negative_w)++;
  }
  return c;
}

std::vector<Ray> rays_down(float extent, int n, uint64_t seed) {
  Pcg32 rng(seed);
  std::vector<Ray> rays;
  for (int i = 0; i < n; ++i) {
    const Vec3 o(extent * (2.0f * rng.next_float() - 1.0f), extent * (2.0f * rng.next_float() - 1.0f), 5.0f);
    rays.push_back(Ray{o, Vec3(0, 0, -1), kInfinity});
  }
  return rays;
}

std::unique_ptr<Shape> quad(bool mirrored) {
  // The quad's uv convention: (0,0), (1,0), (1,1), (0,1) at its corners (geometry/shape_registry.cpp).
  std::vector<Vec2> uv = {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};
  if (mirrored)
    for (Vec2& x : uv) x.x = 1.0f - x.x;
  return std::make_unique<TriangleMesh>(
      std::vector<Vec3>{Vec3(-1, -1, 0), Vec3(1, -1, 0), Vec3(1, 1, 0), Vec3(-1, 1, 0)},
      std::vector<uint32_t>{0, 1, 2, 0, 2, 3}, std::vector<Vec3>{}, uv);
}

TEST(Tangents, QuadFollowsDpDu) {
  const Check c = check_tangents(quad(false), rays_down(0.99f, 200, 1), 1.0f);
  EXPECT_EQ(c.hits, 200);
}

TEST(Tangents, MirroredQuadHasNegativeHandedness) {
  const Check c = check_tangents(quad(true), rays_down(0.99f, 200, 2), -1.0f);
  EXPECT_EQ(c.hits, 200);
}

// A polygon through the shape parser, so its documented (u, v) (along e_u = v1 − v0, e_v = n × e_u) is the one
// checked, with a rotation so that the axes are not the coordinate axes.
TEST(Tangents, PolygonFollowsItsFirstEdge) {
  const std::string json = R"({"type": "polygon", "vertices": [[-1, -1, 0], [1, -0.5, 0], [1.2, 1, 0], [0, 1.5, 0],
    [-1.3, 0.8, 0]], "transform": {"rotate": [0, 0, 1, 30]}})";
  const Json j = Json::parse(json);
  Deferred<Shape> d = parse_shape(JsonObject(j, "", std::make_shared<JsonSource>(JsonSource{"t.json", "."})), nullptr);
  std::unique_ptr<Shape> s = d.take();
  const Check c = check_tangents(std::move(s), rays_down(0.5f, 200, 3), 1.0f);
  EXPECT_EQ(c.hits, 200);
}

TEST(Tangents, SphereFollowsDpDuRightHanded) {
  // Rays towards the centre from random directions (poles excluded: dp/du vanishes there).
  Pcg32 rng(4);
  std::vector<Ray> rays;
  while (rays.size() < 300) {
    const Vec3 d = glm::normalize(Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f));
    if (std::abs(d.y) > 0.95f) continue;
    rays.push_back(Ray{Vec3(0.5f, 0.2f, -0.3f) + 4.0f * d, -d, kInfinity});
  }
  const Check c = check_tangents(std::make_unique<Sphere>(Vec3(0.5f, 0.2f, -0.3f), 1.5f), rays, 1.0f);
  EXPECT_EQ(c.hits, 300);
}

// A smooth height field z = 0.2 sin(x) cos(y) on [-1, 1]², with exact normals and u = (x + 1) / 2 (mirrored:
// u = (1 − x) / 2), v = (y + 1) / 2.
MeshData bumpy_grid(int n, bool mirrored) {
  MeshData m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const float x = -1.0f + 2.0f * i / n, y = -1.0f + 2.0f * j / n;
      m.positions.emplace_back(x, y, 0.2f * std::sin(x) * std::cos(y));
      m.normals.push_back(
          glm::normalize(Vec3(-0.2f * std::cos(x) * std::cos(y), 0.2f * std::sin(x) * std::sin(y), 1.0f)));
      m.uvs.emplace_back(mirrored ? (1.0f - x) * 0.5f : (x + 1.0f) * 0.5f, (y + 1.0f) * 0.5f);
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
    }
  return m;
}

std::unique_ptr<Shape> to_mesh(MeshData m) {
  return std::make_unique<TriangleMesh>(std::move(m.positions), std::move(m.indices), std::move(m.normals),
                                        std::move(m.uvs), std::move(m.tangents));
}

TEST(Tangents, SmoothMeshComputesMikkTSpaceStyleTangents) {
  const Check c = check_tangents(to_mesh(bumpy_grid(16, false)), rays_down(0.95f, 300, 5), 1.0f);
  EXPECT_EQ(c.hits, 300);
}

TEST(Tangents, SmoothMeshWithMirroredUvsHasNegativeHandedness) {
  const Check c = check_tangents(to_mesh(bumpy_grid(16, true)), rays_down(0.95f, 300, 6), -1.0f);
  EXPECT_EQ(c.hits, 300);
}

// The per-vertex tangents of a flat, affinely mapped grid are dp/du itself.
TEST(Tangents, VertexTangentsOfAFlatGridAreDpDu) {
  MeshData m = bumpy_grid(4, false);
  for (Vec3& p : m.positions) p.z = 0.0f;
  for (Vec3& n : m.normals) n = Vec3(0, 0, 1);
  const std::vector<Vec4> t = compute_vertex_tangents(m.positions, m.indices, m.normals, m.uvs);
  ASSERT_EQ(t.size(), m.positions.size());
  for (const Vec4& x : t) {
    EXPECT_NEAR(x.x, 1.0f, 1e-6f);
    EXPECT_NEAR(x.y, 0.0f, 1e-6f);
    EXPECT_NEAR(x.z, 0.0f, 1e-6f);
    EXPECT_EQ(x.w, 1.0f);
  }
}

// Given tangents win over computed ones: a grid whose given tangents point along +y with w = −1 (so b = −cross(n,
// t) points along +x) reports exactly those at every hit, whatever its uvs say.
TEST(Tangents, GivenTangentsAreUsed) {
  MeshData m = bumpy_grid(8, false);
  for (Vec3& p : m.positions) p.z = 0.0f;
  for (Vec3& n : m.normals) n = Vec3(0, 0, 1);
  m.tangents.assign(m.positions.size(), Vec4(0, 1, 0, -1));
  std::vector<std::unique_ptr<Shape>> shapes;
  shapes.push_back(to_mesh(std::move(m)));
  shapes[0]->prepare_tangents();  // must keep the given ones
  EmbreeScene accel(shapes);
  int hits = 0;
  for (const Ray& r : rays_down(0.95f, 100, 7)) {
    SurfaceInteraction si;
    if (!accel.intersect(r, si)) continue;
    ++hits;
    const Vec4 tw = si.shape->tangent(si);
    EXPECT_NEAR(tw.y, 1.0f, 1e-6f);
    EXPECT_EQ(tw.w, -1.0f);
    EXPECT_NEAR((tw.w * glm::cross(si.shading.n, Vec3(tw))).x, 1.0f, 1e-6f);
  }
  EXPECT_EQ(hits, 100);
}

// A mirroring transform reverses the handedness of given tangents (and moves them as vectors).
TEST(Tangents, MirroringTransformFlipsHandedness) {
  MeshData m = bumpy_grid(2, false);
  m.tangents.assign(m.positions.size(), Vec4(1, 0, 0, 1));
  transform_mesh(m, Transform(glm::scale(Mat4(1.0f), Vec3(-2.0f, 1.0f, 1.0f))));
  for (const Vec4& t : m.tangents) {
    EXPECT_EQ(Vec3(t), Vec3(-2, 0, 0));
    EXPECT_EQ(t.w, -1.0f);
  }
}

}  // namespace
}  // namespace kozu::test
