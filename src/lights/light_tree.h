// The light hierarchy: chooses the light for one next-event estimate in proportion to an estimate of the light it
// gives the shading point, in O(log n).
//
// Conty Estevez & Kulla 2018, "Importance Sampling of Many Lights with Adaptive Tree Splitting": a binary BVH over
// the finite emitters (area, polygon and sphere lights, mesh triangles, point and spot lights), each node holding the
// bounds of its lights' emission (lights/light_bounds.h); one stochastic traversal chooses a child with probability
// proportional to its importance at the point (eq. 3), down to a leaf, reusing the one uniform number at every
// level. The build splits where the surface-area-orientation heuristic (§4.4, eq. 2) is lowest over 12 buckets per
// axis. The pmf of a given light (for MIS, when a ray meets it) walks the same choices up from its leaf.
//
// Infinite lights (environment, distant) have no position: they are chosen before the tree with probability
// E∞ / (E∞ + E_tree(p)), their irradiance against the tree root's importance at the point, kept within
// [kMinShare, 1 − kMinShare] so that neither side is starved where the estimate is wrong (occlusion, which no bound
// sees); among themselves in proportion to their irradiance.
//
// Every light that can reach a point keeps a positive probability there (the bounds are conservative), so the
// estimates stay unbiased; lights that emit nothing are never chosen.
#pragma once

#include "lights/light.h"

#include <cstdint>
#include <vector>

namespace kozu {

class LightTree {
 public:
  static constexpr float kMinShare = 0.1f;

  LightTree() = default;
  // lights[i]->index must be i.
  explicit LightTree(const std::vector<const Light*>& lights);

  // The light for a next-event estimate at ctx (u in [0, 1)) and its probability; null when no light can reach it.
  const Light* sample(const LightSampleContext& ctx, float u, float* pmf) const;
  // The probability that sample(ctx, ·) chooses light.
  float pmf(const LightSampleContext& ctx, const Light* light) const;
  bool empty() const { return nodes_.empty() && infinite_.empty(); }
  size_t node_count() const { return nodes_.size(); }

 private:
  struct Node {
    LightCluster cluster;   // phi normalised by the tree's total
    uint32_t second = 0;    // interior: the second child (the first follows the node); 0 for a leaf
    uint32_t light = 0;     // leaf: the light's index
    // Interior nodes whose children's clusters differ only in power (the two triangles of a quad share a box and a
    // cone): the first child's probability, the same at every point (importance is phi times the geometry's
    // term); −1 otherwise, when the importances are evaluated.
    float split = -1.0f;
  };
  // The probability of the first child of the interior node at ctx.p, ctx.n; 0 for both when none can reach it.
  float first_child_probability(const Node& node, const LightSampleContext& ctx, bool* reachable) const;
  struct Entry {
    LightBounds bounds;
    uint32_t light;
  };
  uint32_t build(std::vector<Entry>& entries, size_t begin, size_t end, uint32_t parent, int depth);
  // The share of infinite lights at ctx.
  float infinite_share(const LightSampleContext& ctx) const;

  std::vector<const Light*> lights_;
  std::vector<Node> nodes_;
  std::vector<uint32_t> parent_;   // per node
  std::vector<uint32_t> leaf_of_;  // per light: its leaf, or kNone
  double phi_total_ = 0.0;         // the tree's lights' phi before normalisation
  std::vector<uint32_t> infinite_;  // indices of infinite lights that emit
  std::vector<float> infinite_phi_;
  double infinite_total_ = 0.0;
  static constexpr uint32_t kNone = 0xffffffffu;
};

}  // namespace kozu
