// Probe-ray sampling (bssrdf/probe_sampling.h): the estimator of ∫ R(|x − xo|) dA(x) over a surface is
// unbiased. On a plane and on a sphere (whose area within chord distance r of a point is π r², as on
// the plane: Archimedes) the integral is A · cdf(min(r, 2 radius)), so every channel's mean weight is
// known in closed form.
#include "bssrdf/probe_sampling.h"
#include "core/rng.h"
#include "geometry/embree_scene.h"

#include <gtest/gtest.h>

#include <cmath>

namespace kozu {
namespace {

struct ProbeMean {
  Rgb mean{0.0f};
  Rgb stderr_{0.0f};
  double found = 0;  // fraction of probes that found a hit
};

ProbeMean probe_mean(const EmbreeScene& scene, const SurfaceInteraction& si, const RgbProfile& profile, int n,
                     uint64_t seed) {
  Pcg32 rng(seed);
  double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
  int found = 0;
  uint64_t rays = 0;
  for (int i = 0; i < n; ++i) {
    const Vec4 u(rng.next_float(), rng.next_float(), rng.next_float(), rng.next_float());
    ProbeSample ps;
    if (!sample_probe(scene, si, profile, u, &ps, &rays)) continue;
    ++found;
    for (int c = 0; c < 3; ++c) {
      sum[c] += ps.weight[c];
      sum2[c] += double(ps.weight[c]) * ps.weight[c];
    }
  }
  ProbeMean m;
  for (int c = 0; c < 3; ++c) {
    const double mean = sum[c] / n;
    m.mean[c] = static_cast<float>(mean);
    m.stderr_[c] = static_cast<float>(std::sqrt(std::max(0.0, sum2[c] / n - mean * mean) / n));
  }
  m.found = double(found) / n;
  return m;
}

// Each channel's mean weight is ∫ R_c over the surface within the probes' reach (the largest r_max) and
// within chord distance `chord_max` (the sphere's diameter).
void expect_integral(const ProbeMean& m, const RgbProfile& profile, float chord_max) {
  const float reach = std::max({profile.r_max(0), profile.r_max(1), profile.r_max(2)});
  for (int c = 0; c < 3; ++c) {
    const double expect = profile.channel(c).albedo() * profile.channel(c).cdf(std::min(reach, chord_max));
    EXPECT_NEAR(m.mean[c], expect, 4.0 * m.stderr_[c] + 1e-6) << "channel " << c << " found " << m.found;
  }
}

SurfaceInteraction hit_from_above(const EmbreeScene& scene, const Vec3& o, const Vec3& d) {
  SurfaceInteraction si;
  EXPECT_TRUE(scene.intersect(Ray{o, glm::normalize(d), kInfinity}, si));
  return si;
}

RgbProfile test_profile(float A0, float d0) {
  return RgbProfile({NormalizedDiffusion(A0, d0), NormalizedDiffusion(0.5f, 2.0f * d0), NormalizedDiffusion(1.0f, 4.0f * d0)});
}

TEST(ProbeSampling, PlaneIntegratesTheProfile) {
  std::vector<std::unique_ptr<Shape>> shapes;
  const float h = 50.0f;
  shapes.push_back(std::make_unique<TriangleMesh>(
      std::vector<Vec3>{{-h, -h, 0}, {h, -h, 0}, {h, h, 0}, {-h, h, 0}}, std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
  EmbreeScene scene(shapes);
  const RgbProfile profile = test_profile(0.8f, 0.1f);
  const SurfaceInteraction si = hit_from_above(scene, Vec3(0.3f, -0.2f, 1.0f), Vec3(0, 0, -1));
  const ProbeMean m = probe_mean(scene, si, profile, 400000, 1);
  expect_integral(m, profile, kInfinity);
}

TEST(ProbeSampling, SphereIntegratesTheProfile) {
  std::vector<std::unique_ptr<Shape>> shapes;
  shapes.push_back(std::make_unique<Sphere>(Vec3(0.0f), 0.5f));
  EmbreeScene scene(shapes);
  for (float d0 : {0.01f, 0.05f, 0.2f}) {
    const RgbProfile profile = test_profile(0.8f, d0);
    const SurfaceInteraction si = hit_from_above(scene, Vec3(0.1f, 0.2f, 3.0f), Vec3(-0.1f, -0.2f, -3.0f));
    const ProbeMean m = probe_mean(scene, si, profile, 400000, 2);
    SCOPED_TRACE(d0);
    expect_integral(m, profile, 1.0f);
  }
}

// A closed box with outward faces, from lo to hi.
std::unique_ptr<TriangleMesh> box(const Vec3& lo, const Vec3& hi) {
  std::vector<Vec3> p;
  for (int i = 0; i < 8; ++i) p.emplace_back(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
  // Each face as a quad (a, b, c, d), counter-clockwise seen from outside.
  const uint32_t q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  std::vector<uint32_t> idx;
  for (const auto& f : q) idx.insert(idx.end(), {f[0], f[1], f[2], f[0], f[2], f[3]});
  return std::make_unique<TriangleMesh>(std::move(p), std::move(idx));
}

// A thin slab of thickness h: the back face adds ∫_h^reach R(r) 2πr dr = A (cdf(reach) − cdf(h)) (substitute
// r² = ρ² + h²), the light a thin part transmits.
TEST(ProbeSampling, ThinSlabAddsTheBackFace) {
  std::vector<std::unique_ptr<Shape>> shapes;
  const float h = 0.15f;
  shapes.push_back(box(Vec3(-40, -40, -h), Vec3(40, 40, 0)));
  EmbreeScene scene(shapes);
  const RgbProfile profile = test_profile(0.8f, 0.1f);
  const SurfaceInteraction si = hit_from_above(scene, Vec3(0.2f, 0.1f, 1.0f), Vec3(0, 0, -1));
  const ProbeMean m = probe_mean(scene, si, profile, 400000, 3);
  const float reach = std::max({profile.r_max(0), profile.r_max(1), profile.r_max(2)});
  for (int c = 0; c < 3; ++c) {
    const NormalizedDiffusion& p = profile.channel(c);
    const double expect = p.albedo() * (2.0 * p.cdf(reach) - p.cdf(h));
    EXPECT_NEAR(m.mean[c], expect, 4.0 * m.stderr_[c] + 1e-6) << "channel " << c;
    EXPECT_GT(m.mean[c], p.albedo() * 1.05 * p.cdf(reach)) << "the back face must contribute, channel " << c;
  }
}

// Objects side by side do not bleed: probes from one sphere, touching another with the same profile, only
// return points on their own sphere, and still integrate the profile over it exactly.
TEST(ProbeSampling, NeighbouringObjectsDoNotBleed) {
  std::vector<std::unique_ptr<Shape>> shapes;
  shapes.push_back(std::make_unique<Sphere>(Vec3(0.0f), 0.5f));
  shapes.push_back(std::make_unique<Sphere>(Vec3(1.0f, 0.0f, 0.0f), 0.5f));
  shapes.push_back(box(Vec3(-3, -3, -0.9f), Vec3(3, 3, -0.5f)));  // a floor slab touching from below
  EmbreeScene scene(shapes);
  const RgbProfile profile = test_profile(0.8f, 0.08f);
  // Entry near the contact point with the neighbour.
  const SurfaceInteraction si = hit_from_above(scene, Vec3(0.45f, 0.1f, 2.0f), Vec3(0, 0, -1));
  ASSERT_EQ(si.shape, shapes[0].get());
  Pcg32 rng(9);
  uint64_t rays = 0;
  int found = 0;
  for (int i = 0; i < 100000; ++i) {
    ProbeSample ps;
    if (!sample_probe(scene, si, profile, Vec4(rng.next_float(), rng.next_float(), rng.next_float(), rng.next_float()),
                      &ps, &rays))
      continue;
    ++found;
    ASSERT_EQ(ps.si.shape, shapes[0].get()) << "probe returned a point on another object";
  }
  EXPECT_GT(found, 30000);
  expect_integral(probe_mean(scene, si, profile, 400000, 4), profile, 1.0f);
}

}  // namespace
}  // namespace kozu
