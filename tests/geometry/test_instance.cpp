// Instances (geometry/instance.h): a hit on an instanced object equals the hit on the same geometry with the
// transform applied to its vertices (position, normals, texture coordinates, dp/du, tangent frame), for rotations,
// non-uniform scales and mirrors; a transformed sphere is an exact ellipsoid; probe rays tell instances apart;
// the scene keys and their refusals.
#include "core/error.h"
#include "core/rng.h"
#include "core/warp.h"
#include "geometry/instance.h"
#include "scene/scene_loader.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace kozu {
namespace {

// A smooth-shaded, textured surface (a bumpy height field with per-vertex normals and texture coordinates) in the
// box [-1, 1] x [-0.3, 0.3] x [-1, 1], as an OBJ file in the temporary folder.
std::filesystem::path write_bumpy_obj() {
  const std::filesystem::path file = std::filesystem::temp_directory_path() / "kozu-test-instance-bumpy.obj";
  std::ofstream out(file);
  const int n = 12;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const float x = -1.0f + 2.0f * i / n, z = -1.0f + 2.0f * j / n;
      const float y = 0.3f * std::sin(3.0f * x) * std::cos(2.0f * z);
      out << fmt::format("v {} {} {}\nvn {} {} {}\nvt {} {}\n", x, y, z,
                         -0.9f * std::cos(3.0f * x) * std::cos(2.0f * z), 1.0f,
                         0.6f * std::sin(3.0f * x) * std::sin(2.0f * z), 0.7f * i / n + 0.1f * j / n, float(j) / n);
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i + 1, b = a + 1, c = a + n + 1, d = c + 1;
      out << fmt::format("f {0}/{0}/{0} {1}/{1}/{1} {2}/{2}/{2}\nf {2}/{2}/{2} {1}/{1}/{1} {3}/{3}/{3}\n", a, c, b, d);
    }
  return file;
}

std::string bumpy_mesh_json(const std::string& extra) {
  return fmt::format(R"({{"type": "mesh", "file": "{}"{}}})", write_bumpy_obj().string(), extra);
}

std::unique_ptr<Scene> load(const std::string& objects, const std::string& shapes) {
  return load_scene_text(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
    "materials": {"m": {"type": "diffuse"}}, "objects": {)" +
                             objects + R"(}, "shapes": [)" + shapes + R"(]})",
                         "scene.json", ".");
}

TEST(Instance, HitsEqualTheTransformedGeometry) {
  for (const char* xf : {R"({"rotate": [1, 2, 3, 40], "translate": [0.2, -0.1, 0.3]})",
                         R"({"scale": [1.5, 0.4, 0.8], "rotate": [0, 1, 1, 30], "translate": [0, 0.1, 0]})",
                         R"({"scale": [-1, 1, 1], "rotate": [1, 0, 0, 70]})"}) {
    const std::string mesh = bumpy_mesh_json(R"(, "material": "m")");
    const auto instanced = load(R"("bump": [)" + mesh + "]",
                                fmt::format(R"({{"type": "instance", "object": "bump", "transform": {}}})", xf));
    const auto baked = load("", bumpy_mesh_json(fmt::format(R"(, "material": "m", "transform": {})", xf)));
    Pcg32 rng(11);
    int hits = 0;
    for (int k = 0; k < 2000; ++k) {
      const Vec3 o = 4.0f * warp::square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
      const Vec3 target(0.8f * (2.0f * rng.next_float() - 1.0f), 0.2f * (2.0f * rng.next_float() - 1.0f),
                        0.8f * (2.0f * rng.next_float() - 1.0f));
      const Ray r{o, glm::normalize(target - o), kInfinity};
      SurfaceInteraction a, b;
      const bool ha = instanced->intersect(r, a), hb = baked->intersect(r, b);
      ASSERT_EQ(ha, hb) << xf << " ray " << k;
      if (!ha) continue;
      ++hits;
      ASSERT_NE(a.instance, nullptr);
      EXPECT_EQ(b.instance, nullptr);
      EXPECT_NEAR(a.t, b.t, 1e-4f) << xf;
      EXPECT_LT(glm::length(a.p - b.p), 1e-4f) << xf;
      EXPECT_GT(glm::dot(a.ng, b.ng), 1.0f - 1e-5f) << xf;
      EXPECT_GT(glm::dot(a.shading.n, b.shading.n), 1.0f - 1e-4f) << xf;
      EXPECT_EQ(a.front_face, b.front_face) << xf;
      EXPECT_LT(glm::length(a.uv - b.uv), 1e-4f) << xf;
      Vec3 adu, adv, bdu, bdv;
      surface_uv_derivatives(a, &adu, &adv);
      surface_uv_derivatives(b, &bdu, &bdv);
      EXPECT_LT(glm::length(adu - bdu), 1e-3f * glm::length(bdu)) << xf;
      EXPECT_LT(glm::length(adv - bdv), 1e-3f * glm::length(bdv)) << xf;
      const Vec4 ta = surface_tangent(a), tb = surface_tangent(b);
      EXPECT_GT(glm::dot(Vec3(ta), Vec3(tb)), 1.0f - 1e-3f) << xf;
      EXPECT_EQ(ta.w, tb.w) << xf;
      // The spawned ray leaves the surface without hitting it again.
      SurfaceInteraction again;
      const Vec3 out = a.front_face ? a.ng : -a.ng;
      const Ray leave = a.spawn_ray(glm::normalize(out + 0.3f * glm::normalize(r.d + out)));
      if (instanced->intersect(leave, again)) {
        EXPECT_GT(again.t, 1e-3f) << xf;
      }
    }
    EXPECT_GT(hits, 500) << xf;
  }
}

// A sphere under a non-uniform scale is an ellipsoid: every hit lies on (x/a)^2 + (y/b)^2 + (z/c)^2 = 1 (after the
// translation) with the normal along the equation's gradient; under a similarity it stays a sphere (no instance).
TEST(Instance, TransformedSphereIsAnEllipsoid) {
  const auto scene = load_scene_text(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
    "materials": {"m": {"type": "diffuse"}},
    "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m",
                "transform": {"scale": [2, 0.5, 1], "translate": [0.5, 0, 0]}},
               {"type": "sphere", "center": [1, 0, 0], "radius": 1, "material": "m",
                "transform": {"scale": 2, "rotate": [0, 0, 1, 90], "translate": [0, 0, 10]}}]})",
                                     "scene.json", ".");
  EXPECT_NE(dynamic_cast<const Instance*>(scene->shapes[0].get()), nullptr);
  const auto* sphere = dynamic_cast<const Sphere*>(scene->shapes[1].get());
  ASSERT_NE(sphere, nullptr);
  EXPECT_LT(glm::length(sphere->center() - Vec3(0, 2, 10)), 1e-5f);
  EXPECT_FLOAT_EQ(sphere->radius(), 2.0f);
  Pcg32 rng(5);
  int hits = 0;
  for (int k = 0; k < 1000; ++k) {
    const Vec3 o = 6.0f * warp::square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
    const Vec3 target(0.5f + 1.5f * (2.0f * rng.next_float() - 1.0f), 0.4f * (2.0f * rng.next_float() - 1.0f), 0.0f);
    const Ray r{o, glm::normalize(target - o), kInfinity};
    SurfaceInteraction si;
    if (!scene->intersect(r, si) || si.instance == nullptr) continue;
    ++hits;
    const Vec3 q = si.p - Vec3(0.5f, 0, 0);
    EXPECT_NEAR(q.x * q.x / 4.0f + q.y * q.y / 0.25f + q.z * q.z, 1.0f, 1e-4f);
    const Vec3 grad = glm::normalize(Vec3(q.x / 4.0f, q.y / 0.25f, q.z));
    EXPECT_GT(glm::dot(si.ng, grad), 1.0f - 1e-5f);
    EXPECT_TRUE(si.front_face);
  }
  EXPECT_GT(hits, 300);
}

// Subsurface probe rays look for hits on the shape they left; with instances, on the same instance: two instances
// of one object stacked along a ray, each seen only by its own query.
TEST(Instance, ProbeRaysTellInstancesApart) {
  const std::string quad = R"({"type": "quad", "material": "m",
    "vertices": [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]})";
  const auto scene = load(R"("q": [)" + quad + "]",
                          R"({"type": "instance", "object": "q", "transform": {"translate": [0, 0, 1]}},
                             {"type": "instance", "object": "q", "transform": {"translate": [0, 0, -1]}})");
  const Ray r{Vec3(0.1f, 0.2f, 5), Vec3(0, 0, -1), kInfinity};
  SurfaceInteraction first;
  ASSERT_TRUE(scene->intersect(r, first));
  EXPECT_NEAR(first.p.z, 1.0f, 1e-5f);
  const auto* a = dynamic_cast<const Instance*>(scene->shapes[0].get());
  const auto* b = dynamic_cast<const Instance*>(scene->shapes[1].get());
  ASSERT_TRUE(a && b);
  EXPECT_EQ(first.instance, a);
  SurfaceInteraction hits[4];
  uint64_t rays = 0;
  ASSERT_EQ(scene->accel().intersect_shape(r, first.shape, b, hits, 4, &rays), 1);
  EXPECT_NEAR(hits[0].p.z, -1.0f, 1e-5f);
  EXPECT_EQ(hits[0].instance, b);
  ASSERT_EQ(scene->accel().intersect_shape(r, first.shape, a, hits, 4, &rays), 1);
  EXPECT_NEAR(hits[0].p.z, 1.0f, 1e-5f);
}

std::string instance_error(const std::string& objects, const std::string& shapes) {
  try {
    load(objects, shapes);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Instance, KeysAndRefusals) {
  const std::string quad =
      R"({"type": "quad", "material": "m", "vertices": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])";
  EXPECT_EQ(instance_error(R"("q": [)" + quad + "}]", R"({"type": "instance", "object": "q"})"), "");
  EXPECT_EQ(instance_error(R"("q": [)" + quad + "}]", R"({"type": "instance", "object": "tree"})"),
            "scene.json: /shapes/0/object: unknown object 'tree' (defined in \"objects\": 'q')");
  EXPECT_EQ(instance_error(R"("q": [)" + quad + "}]", R"({"type": "instance", "object": "q", "material": "m"})"),
            "scene.json: /shapes/0/material: an instance takes its materials and media from its object's shapes: "
            "remove 'material'");
  EXPECT_EQ(instance_error(R"("q": [)" + quad + R"(, "emission": 1}])", R"({"type": "instance", "object": "q"})"),
            "scene.json: /objects/q/0/emission: an object's shapes cannot emit light (an area light is one surface "
            "in the scene): make the emitter a shape of its own");
  EXPECT_EQ(instance_error(R"("q": [{"type": "instance", "object": "q"}])", R"({"type": "instance", "object": "q"})"),
            "scene.json: /objects/q/0/type: an object's shapes cannot be of type 'instance' (objects do not nest)");
  EXPECT_EQ(instance_error(R"("q": [])", R"({"type": "instance", "object": "q"})"),
            "scene.json: /objects/q: an object needs at least one shape");
  EXPECT_EQ(instance_error("", R"({"type": "sphere", "center": [0, 0, 0], "radius": 1, "emission": 1,
                                   "transform": {"scale": [1, 2, 1]}})"),
            "scene.json: /shapes/0/transform: an emitting sphere takes rotations, translations and uniform scales "
            "only (its light samples a sphere); use an emitting mesh for an ellipsoid");
}

}  // namespace
}  // namespace kozu
