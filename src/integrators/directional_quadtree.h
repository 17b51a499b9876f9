// A learnt distribution of directions: a quadtree over the cylindrical square of the sphere, the directional half of
// practical path guiding's SD-tree.
//
// Müller, Gross, Novák 2017, "Practical Path Guiding for Efficient Light-Transport Simulation", Computer Graphics
// Forum 36(4): §3.2 (the D-tree: a quadtree over the world-space cylindrical coordinates (cos θ, φ), whose uniform
// square maps to the uniform sphere, so a density on the square divided by 4π is one per solid angle), §3.3 (sampling
// by descending with the quadrants' energies, pdf the product of the descents' 4·share), §4.2 (refinement: a quadrant
// holding more than ρ = 0.01 of the total energy is subdivided, the others collapsed, at most 20 levels deep).
//
// Equation map: cylindrical mapping (§3.2) → to_square / to_direction; sampling and pdf (§3.3) → sample, pdf;
// refinement (§4.2) → refined.
//
// Two sets of sums per node: `sum`, the energies the tree samples with (learnt in the previous pass, frozen), and the
// records of the pass in progress. A record is Li(ω)/p(ω) (incident radiance over the density it was sampled with, an
// estimate of Li's integral over its quadrant). Deviation from the paper: records are added in 2^-20 fixed point with
// stochastic rounding (a caller's hash for the dither), not in floats, so that the sums, and so the learnt
// distribution, do not depend on the order in which threads add them: a render is the same image at any thread count.
#pragma once

#include "core/math.h"

#include <array>
#include <cstdint>
#include <vector>

namespace kozu {

class DirectionalQuadtree {
 public:
  // The paper's refinement constants (§4.2).
  static constexpr float kSubdivideShare = 0.01f;  // ρ
  static constexpr int kMaxDepth = 20;

  // One node with four quadrants, nothing learnt: empty() until refined from records.
  DirectionalQuadtree() : nodes_(1), records_(1) {}

  // Cylindrical coordinates (§3.2): (cos θ + 1) / 2 and φ / 2π, world space; and back.
  static Vec2 to_square(const Vec3& d);
  static Vec3 to_direction(const Vec2& p);

  // Whether the tree has energy to sample with (else sample and pdf must not be used).
  bool empty() const { return empty_; }
  // A direction from u in [0,1)², and its solid-angle density (> 0 unless the tree is empty).
  Vec3 sample(const Vec2& u, float* pdf) const;
  // The solid-angle density of sample at d (0 in quadrants without energy).
  float pdf(const Vec3& d) const;

  // Adds the record `value` (≥ 0, finite) at direction d; safe from many threads at once. dither: any 32 bits that
  // vary from record to record (the stochastic rounding's).
  void record(const Vec3& d, float value, uint32_t dither) const;
  // The next pass's tree: the structure refined by this pass's records, which become its sampling energies (§4.2);
  // its records start at zero. Where nothing was recorded, the tree keeps its structure and energies.
  DirectionalQuadtree refined() const;

  size_t node_count() const { return nodes_.size(); }
  int depth() const;

 private:
  // 32 bytes: what sampling reads, apart from the records it never reads.
  struct Node {
    std::array<uint32_t, 4> child{};  // 0: the quadrant is a leaf
    std::array<float, 4> p{};         // the quadrants' probabilities given the node (their energies' shares)
  };
  // Quadrant q of a node covers [x, x + 1/2) × [y, y + 1/2) of its square, x = (q & 1) / 2, y = (q >> 1) / 2.
  double subtree_records(uint32_t node, std::vector<double>& totals) const;
  std::vector<Node> nodes_;
  // This pass's records per node and quadrant, 2^-20 fixed point, at leaf quadrants only (std::atomic_ref).
  mutable std::vector<std::array<uint64_t, 4>> records_;
  bool empty_ = true;
};

}  // namespace kozu
