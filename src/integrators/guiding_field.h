// The learnt incident radiance of practical path guiding: a binary tree over space whose leaves each hold a
// directional quadtree (integrators/directional_quadtree.h) — the SD-tree.
//
// Müller, Gross, Novák 2017, "Practical Path Guiding for Efficient Light-Transport Simulation", Computer Graphics
// Forum 36(4): §3.1 (the S-tree: a binary tree over the scene's bounding cube, split in the middle along x, y, z in
// turn), §4.1 (spatial refinement: a leaf that received more than c·sqrt(2^k) path vertices in pass k is split,
// its children starting from copies of its directional tree), §4.3 (passes of doubling size; the paper's c = 12000
// for 2^k samples per pixel of its images).
//
// Deviation: the split threshold is kSplitPerRootPath · sqrt(N) vertices, N the pass's paths. The paper's c·sqrt(2^k),
// with its 1280 × 720 images, is the same rule with c / sqrt(921600) = 12.5 per square root of a path, which keeps
// the tree's resolution the same whatever the image's size (kozu trains on a quarter of the pixels:
// render/guiding_training.h). Measured on bench/cycles' window-lit interior (256², 64 spp): variance 1.05e-4 with 4,
// 8.8e-5 with 12.5, 1.04e-4 with 50, and 1.20e-4 with the paper's c·sqrt(2^k) unscaled (1.02e-4 unguided).
//
// Use: sample and take pdfs from distribution(p), which stays fixed during a pass; record() adds the pass's records
// from any number of threads; refine() between passes makes them the next pass's distribution.
#pragma once

#include "integrators/directional_quadtree.h"

#include <cstdint>
#include <vector>

namespace kozu {

class GuidingField {
 public:
  static constexpr float kSplitPerRootPath = 12.5f;

  // The cube of half-size `radius` around `center` (a scene's bounding sphere's; points outside are clamped in).
  GuidingField(const Vec3& center, float radius);

  // The directional distribution at p, or null where nothing has been learnt yet.
  const DirectionalQuadtree* distribution(const Vec3& p) const {
    const DirectionalQuadtree& t = trees_[leaf(p)];
    return t.empty() ? nullptr : &t;
  }
  // One path vertex at p: Li(ω)/p(ω) of its direction d (0: a vertex that brought nothing counts too, for the
  // spatial refinement), safe from many threads at once. dither: 32 bits that vary between records.
  void record(const Vec3& p, const Vec3& d, float value, uint32_t dither) const;
  // Ends a pass of `paths` paths: splits the leaves that received more than kSplitPerRootPath · sqrt(paths) vertices
  // (§4.1) and makes each leaf's records its distribution (§4.2). Deterministic: the result depends on the records'
  // sums only.
  void refine(uint64_t paths);

  int passes() const { return passes_; }
  size_t leaves() const { return trees_.size(); }
  size_t directional_nodes() const;
  size_t bytes() const;

 private:
  struct Node {
    uint32_t child[2] = {0, 0};  // 0: a leaf
    uint32_t tree = 0;           // a leaf's directional tree
    mutable uint64_t vertices = 0;  // this pass's records (std::atomic_ref)
  };
  uint32_t leaf_node(const Vec3& p) const;
  uint32_t leaf(const Vec3& p) const { return nodes_[leaf_node(p)].tree; }
  void split(uint32_t node, uint64_t vertices, uint64_t threshold, std::vector<DirectionalQuadtree>& trees);
  Vec3 lo_, size_;
  std::vector<Node> nodes_;
  std::vector<DirectionalQuadtree> trees_;
  int passes_ = 0;
};

}  // namespace kozu
