#include "integrators/guiding_field.h"

#include <algorithm>
#include <atomic>
#include <cmath>

namespace kozu {

GuidingField::GuidingField(const Vec3& center, float radius)
    : lo_(center - Vec3(std::max(radius, 1e-6f))), size_(Vec3(2.0f * std::max(radius, 1e-6f))), nodes_(1), trees_(1) {}

uint32_t GuidingField::leaf_node(const Vec3& p) const {
  const Vec3 c = glm::clamp((p - lo_) / size_, Vec3(0.0f), Vec3(0.99999994f));
  // 32-bit fixed point per axis: the level's half is the next bit, no float chain from level to level.
  uint32_t q[3] = {0x80000000u, 0x80000000u, 0x80000000u};  // NaN: any leaf
  if (c.x == c.x && c.y == c.y && c.z == c.z)
    for (int a = 0; a < 3; ++a) q[a] = uint32_t(double(c[a]) * 4294967296.0);
  const Node* nodes = nodes_.data();
  uint32_t n = 0;
  // x, y, z in turn.
  for (int bit = 31;; --bit)
    for (int axis = 0; axis < 3; ++axis) {
      if (nodes[n].child[0] == 0) return n;
      n = nodes[n].child[(q[axis] >> bit) & 1u];
    }
}

void GuidingField::record(const Vec3& p, const Vec3& d, float value, uint32_t dither) const {
  const Node& node = nodes_[leaf_node(p)];
  std::atomic_ref<uint64_t>(node.vertices).fetch_add(1, std::memory_order_relaxed);
  trees_[node.tree].record(d, value, dither);
}

// §4.1: a leaf splits in two while its share of the vertices exceeds the threshold; each half is assumed to have
// received half of them, and starts from a copy of the leaf's directional tree.
void GuidingField::split(uint32_t n, uint64_t vertices, uint64_t threshold, std::vector<DirectionalQuadtree>& trees) {
  if (vertices <= threshold) return;
  const uint32_t tree = nodes_[n].tree;
  for (int k = 0; k < 2; ++k) {
    Node child;
    child.tree = k == 0 ? tree : uint32_t(trees.size());
    if (k == 1) trees.push_back(trees[tree]);
    nodes_[n].child[k] = uint32_t(nodes_.size());
    nodes_.push_back(child);
  }
  const uint32_t a = nodes_[n].child[0], b = nodes_[n].child[1];
  split(a, vertices / 2, threshold, trees);
  split(b, vertices / 2, threshold, trees);
}

void GuidingField::refine(uint64_t paths) {
  std::vector<DirectionalQuadtree> trees;
  trees.reserve(trees_.size());
  for (const DirectionalQuadtree& t : trees_) trees.push_back(t.refined());
  const uint64_t threshold = std::max<uint64_t>(1, uint64_t(kSplitPerRootPath * std::sqrt(double(paths))));
  const size_t before = nodes_.size();
  for (size_t n = 0; n < before; ++n) {
    if (nodes_[n].child[0] != 0) continue;
    const uint64_t vertices = nodes_[n].vertices;
    split(uint32_t(n), vertices, threshold, trees);
  }
  for (Node& node : nodes_) node.vertices = 0;
  trees_ = std::move(trees);
  ++passes_;
}

size_t GuidingField::directional_nodes() const {
  size_t n = 0;
  for (const DirectionalQuadtree& t : trees_) n += t.node_count();
  return n;
}

size_t GuidingField::bytes() const {
  return nodes_.size() * sizeof(Node) + trees_.size() * sizeof(DirectionalQuadtree) + directional_nodes() * 64;  // a node and its records
}

}  // namespace kozu
