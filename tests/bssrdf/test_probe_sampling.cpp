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

}  // namespace
}  // namespace kozu
