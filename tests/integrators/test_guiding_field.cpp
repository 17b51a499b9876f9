// The SD-tree of path guiding (integrators/directional_quadtree.h, integrators/guiding_field.h): its directional
// distributions sample what their pdf says (chi-square), integrate to one, follow what was recorded, refine as the
// paper's rules say, and do not depend on the order of the records.
#include "integrators/guiding_field.h"

#include "core/rng.h"
#include "support/chi2.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <vector>

namespace kozu::test {
namespace {

// Records of a lobe around `axis` (values exp(k (cos − 1))) plus a faint uniform floor, at directions drawn
// uniformly: each record is value / (1/4π), an unbiased estimate of the lobe's integral over its quadrant.
void record_lobe(const DirectionalQuadtree& tree, const Vec3& axis, float k, int count, uint64_t seed) {
  Pcg32 rng(seed);
  for (int i = 0; i < count; ++i) {
    const Vec3 d = DirectionalQuadtree::to_direction(Vec2(rng.next_float(), rng.next_float()));
    const float value = std::exp(k * (glm::dot(d, axis) - 1.0f)) + 0.01f;
    tree.record(d, value * 4.0f * kPi, rng.next_u32());
  }
}

DirectionalQuadtree learnt_lobe(const Vec3& axis, float k) {
  DirectionalQuadtree tree;
  for (int pass = 0; pass < 3; ++pass) {
    record_lobe(tree, axis, k, 200'000, 11 + pass);
    tree = tree.refined();
  }
  return tree;
}

TEST(DirectionalQuadtree, CylindricalMappingRoundTrips) {
  Pcg32 rng(3);
  for (int i = 0; i < 10'000; ++i) {
    const Vec2 p(rng.next_float(), rng.next_float());
    const Vec3 d = DirectionalQuadtree::to_direction(p);
    EXPECT_NEAR(glm::length(d), 1.0f, 1e-5f);
    const Vec2 back = DirectionalQuadtree::to_square(d);
    EXPECT_NEAR(back.x, p.x, 2e-6f);
    // φ near 0 and 2π are the same direction.
    const float dy = std::abs(back.y - p.y);
    EXPECT_LT(std::min(dy, 1.0f - dy), 2e-5f) << p.x << " " << p.y;
  }
}

TEST(DirectionalQuadtree, EmptyUntilSomethingIsRecorded) {
  DirectionalQuadtree tree;
  EXPECT_TRUE(tree.empty());
  EXPECT_TRUE(tree.refined().empty());
  tree.record(Vec3(0, 0, 1), 0.0f, 0);  // nothing to learn from
  EXPECT_TRUE(tree.refined().empty());
  tree.record(Vec3(0, 0, 1), 1.0f, 0);
  EXPECT_FALSE(tree.refined().empty());
}

TEST(DirectionalQuadtree, Chi2AgainstItsPdf) {
  const Vec3 axis = glm::normalize(Vec3(0.3f, -0.5f, 0.8f));
  const DirectionalQuadtree tree = learnt_lobe(axis, 30.0f);
  ASSERT_FALSE(tree.empty());
  ASSERT_GT(tree.depth(), 3);  // the lobe made it refine
  // Bins on the tree's own cells' edges (dyadic in cos θ and φ, 2:1), so that the pdf is smooth inside the bins down
  // to the tree's sixth level; deeper cells are resolved by more quadrature points.
  Chi2Options options;
  options.theta_bins = 64;
  options.phi_bins = 128;
  options.integration_points = 24;
  options.sample_count = 2'000'000;
  int64_t samples = 0, disagree = 0;
  const Chi2Result r = chi2_test(
      [&](const Vec2& u) -> std::optional<Vec3> {
        float pdf = 0.0f;
        const Vec3 d = tree.sample(u, &pdf);
        ++samples;
        disagree += std::abs(pdf - tree.pdf(d)) > 1e-4f * pdf;
        return d;
      },
      [&](const Vec3& w) { return double(tree.pdf(w)); }, options);
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_integral, 1.0, 1e-3);
  // The density sample reports is the pdf's at the sample, but for directions within float rounding of a cell's
  // edge, which the round trip through the direction may put in the neighbouring cell (the path uses pdf() alone).
  EXPECT_LT(disagree, samples / 10'000) << disagree << " of " << samples;
}

TEST(DirectionalQuadtree, FollowsWhatWasRecorded) {
  const Vec3 axis(0.0f, 0.0f, -1.0f);
  const DirectionalQuadtree tree = learnt_lobe(axis, 30.0f);
  // The lobe's integral is 2π/k ≈ 0.21 of the floor's 4π · 0.01 = 0.126 plus itself: over 60 % of the samples land
  // within 30° of its axis, which holds 6.7 % of the sphere.
  Pcg32 rng(5);
  int near = 0;
  constexpr int kCount = 100'000;
  for (int i = 0; i < kCount; ++i) {
    float pdf;
    if (glm::dot(tree.sample(Vec2(rng.next_float(), rng.next_float()), &pdf), axis) > std::cos(kPi / 6)) ++near;
  }
  EXPECT_GT(near, kCount * 0.6);
  EXPECT_GT(tree.pdf(axis), 5.0f * tree.pdf(-axis));
}

TEST(DirectionalQuadtree, RefinementFollowsTheSharesRule) {
  DirectionalQuadtree tree;
  // Everything in one direction: the path to it subdivides down to the maximum depth, the rest stays coarse.
  for (int i = 0; i < 1000; ++i) tree.record(Vec3(0.0f, 0.0f, 1.0f), 1.0f, uint32_t(i));
  for (int pass = 0; pass < DirectionalQuadtree::kMaxDepth + 2; ++pass) {
    const DirectionalQuadtree next = tree.refined();
    for (int i = 0; i < 1000; ++i) next.record(Vec3(0.0f, 0.0f, 1.0f), 1.0f, uint32_t(i));
    tree = next;
  }
  EXPECT_EQ(tree.depth(), DirectionalQuadtree::kMaxDepth);
  // One chain of nodes (each with one subdivided quadrant), not a full tree.
  EXPECT_EQ(tree.node_count(), size_t(DirectionalQuadtree::kMaxDepth));
}

TEST(DirectionalQuadtree, RecordOrderDoesNotChangeTheDistribution) {
  struct Record {
    Vec3 d;
    float value;
    uint32_t dither;
  };
  std::vector<Record> records;
  Pcg32 rng(9);
  for (int i = 0; i < 50'000; ++i) {
    const Vec3 d = DirectionalQuadtree::to_direction(Vec2(rng.next_float(), rng.next_float()));
    records.push_back({d, std::exp(8.0f * d.x) * rng.next_float(), rng.next_u32()});
  }
  auto learn = [&](const std::vector<Record>& rs) {
    DirectionalQuadtree t;
    for (int pass = 0; pass < 2; ++pass) {
      for (const Record& r : rs) t.record(r.d, r.value, r.dither);
      t = t.refined();
    }
    return t;
  };
  const DirectionalQuadtree a = learn(records);
  std::reverse(records.begin(), records.end());
  const DirectionalQuadtree b = learn(records);
  ASSERT_EQ(a.node_count(), b.node_count());
  for (int i = 0; i < 1000; ++i) {
    const Vec3 d = DirectionalQuadtree::to_direction(Vec2(rng.next_float(), rng.next_float()));
    const float pa = a.pdf(d), pb = b.pdf(d);
    EXPECT_EQ(std::memcmp(&pa, &pb, sizeof(float)), 0);
  }
}

TEST(GuidingField, SplitsWhereTheVerticesAre) {
  GuidingField field(Vec3(0.0f), 1.0f);
  EXPECT_EQ(field.distribution(Vec3(0.5f)), nullptr);  // nothing learnt
  // 40 000 vertices, all in the cube's corner near (0.9, 0.9, 0.9); the threshold for 10 000 paths is 1250.
  Pcg32 rng(2);
  for (int i = 0; i < 40'000; ++i) {
    const Vec3 p = Vec3(0.8f) + 0.2f * Vec3(rng.next_float(), rng.next_float(), rng.next_float());
    field.record(p, Vec3(0, 0, 1), 1.0f, rng.next_u32());
  }
  field.refine(10'000);
  EXPECT_EQ(field.passes(), 1);
  // Counts say how many, not where: the root halves until 40 000 / 2^k ≤ 1250, into 32 leaves of 0.5 × 0.5 × 1.
  EXPECT_EQ(field.leaves(), 32u);
  // The next pass's vertices in the same corner all fall in one of them, which alone splits again.
  for (int i = 0; i < 40'000; ++i) {
    const Vec3 p = Vec3(0.8f) + 0.2f * Vec3(rng.next_float(), rng.next_float(), rng.next_float());
    field.record(p, Vec3(0, 0, 1), 1.0f, rng.next_u32());
  }
  field.refine(10'000);
  EXPECT_EQ(field.leaves(), 32u - 1u + 32u);
  // Every leaf starts from the distribution learnt at the root, including those that saw no vertex.
  ASSERT_NE(field.distribution(Vec3(0.9f)), nullptr);
  ASSERT_NE(field.distribution(Vec3(-0.9f)), nullptr);
  EXPECT_GT(field.distribution(Vec3(0.9f))->pdf(Vec3(0, 0, 1)), 1.0f);
  // Points outside the cube, and NaN, find a leaf.
  EXPECT_NE(field.distribution(Vec3(50.0f)), nullptr);
  EXPECT_NE(field.distribution(Vec3(std::nanf(""))), nullptr);
}

}  // namespace
}  // namespace kozu::test
