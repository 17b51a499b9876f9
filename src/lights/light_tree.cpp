#include "lights/light_tree.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace kozu {

namespace {

// M_Ω of Conty Estevez & Kulla 2018 §4.4: the solid-angle measure of an orientation cone, normals within θo
// emitting up to θe beyond them.
float orientation_measure(const DirectionCone& c) {
  const float theta_w = std::min(c.theta_o + c.theta_e, kPi);
  const float sin_o = std::sin(c.theta_o), cos_o = std::cos(c.theta_o);
  return 2.0f * kPi * (1.0f - cos_o) +
         0.5f * kPi * (2.0f * theta_w * sin_o - std::cos(c.theta_o - 2.0f * theta_w) - 2.0f * c.theta_o * sin_o + cos_o);
}

// The cost of a cluster (eq. 2): power × orientation measure × size; the size is the box's area plus its squared
// diagonal, so that clusters of points and of collinear lights still compare.
float cluster_cost(const LightBounds& b) {
  if (!(b.phi > 0.0f)) return 0.0f;
  const Vec3 e = b.hi - b.lo;
  const float size = 2.0f * (e.x * e.y + e.y * e.z + e.z * e.x) + glm::dot(e, e);
  return b.phi * orientation_measure(b.cone) * size;
}

}  // namespace

LightTree::LightTree(const std::vector<const Light*>& lights) : lights_(lights), leaf_of_(lights.size(), kNone) {
  std::vector<Entry> entries;
  for (size_t i = 0; i < lights.size(); ++i) {
    const LightBounds b = lights[i]->bounds();
    if (!(b.phi > 0.0f) || !std::isfinite(b.phi)) continue;  // emits nothing: never chosen
    if (b.infinite) {
      infinite_.push_back(static_cast<uint32_t>(i));
      infinite_phi_.push_back(b.phi);
      infinite_total_ += b.phi;
    } else {
      entries.push_back(Entry{b, static_cast<uint32_t>(i)});
      phi_total_ += b.phi;
    }
  }
  if (entries.empty()) return;
  const float scale = static_cast<float>(1.0 / phi_total_);
  for (Entry& e : entries) e.bounds.phi *= scale;  // relative powers: importances stay within float's range
  nodes_.reserve(2 * entries.size() - 1);
  parent_.reserve(2 * entries.size() - 1);
  build(entries, 0, entries.size(), kNone, 0);
}

uint32_t LightTree::build(std::vector<Entry>& entries, size_t begin, size_t end, uint32_t parent, int depth) {
  const uint32_t index = static_cast<uint32_t>(nodes_.size());
  nodes_.emplace_back();
  parent_.push_back(parent);
  if (end - begin == 1) {
    nodes_[index].cluster = LightCluster::from(entries[begin].bounds);
    nodes_[index].light = entries[begin].light;
    leaf_of_[entries[begin].light] = index;
    return index;
  }
  LightBounds all;
  Vec3 c_lo(kInfinity), c_hi(-kInfinity);
  for (size_t i = begin; i < end; ++i) {
    all = LightBounds::merge(all, entries[i].bounds);
    c_lo = glm::min(c_lo, entries[i].bounds.centre());
    c_hi = glm::max(c_hi, entries[i].bounds.centre());
  }
  const Vec3 extent = all.hi - all.lo;
  const float max_extent = std::max({extent.x, extent.y, extent.z});

  // The split of least cost over kBuckets buckets of the centroids along each axis (eq. 2, with the regularisation
  // Kr = the node's largest extent over its extent along the axis, against thin slabs).
  constexpr int kBuckets = 12;
  // The bucket of an entry's centroid along axis (the centroids span c_lo to c_hi).
  const auto bucket_of = [&](const Entry& e, int axis) {
    const float t = (e.bounds.centre()[axis] - c_lo[axis]) / (c_hi[axis] - c_lo[axis]);
    return std::min(kBuckets - 1, static_cast<int>(kBuckets * t));
  };
  float best_cost = kInfinity;
  int best_axis = -1, best_bucket = 0;
  for (int axis = 0; axis < 3 && depth < 64; ++axis) {
    if (!(c_hi[axis] - c_lo[axis] > 0.0f)) continue;
    std::array<LightBounds, kBuckets> buckets;
    for (size_t i = begin; i < end; ++i) {
      LightBounds& b = buckets[bucket_of(entries[i], axis)];
      b = LightBounds::merge(b, entries[i].bounds);
    }
    const float kr = extent[axis] > 0.0f ? max_extent / extent[axis] : 1.0f;
    for (int split = 1; split < kBuckets; ++split) {
      LightBounds left, right;
      for (int k = 0; k < split; ++k) left = LightBounds::merge(left, buckets[k]);
      for (int k = split; k < kBuckets; ++k) right = LightBounds::merge(right, buckets[k]);
      if (!(left.phi > 0.0f) || !(right.phi > 0.0f)) continue;
      const float cost = kr * (cluster_cost(left) + cluster_cost(right));
      if (cost < best_cost) {
        best_cost = cost;
        best_axis = axis;
        best_bucket = split;
      }
    }
  }
  size_t middle;
  if (best_axis >= 0) {
    const auto it = std::partition(entries.begin() + begin, entries.begin() + end,
                                   [&](const Entry& e) { return bucket_of(e, best_axis) < best_bucket; });
    middle = static_cast<size_t>(it - entries.begin());
  } else {
    // Coincident centroids (or a deep tree): halves by count along the widest axis, which bounds the depth.
    int axis = 0;
    const Vec3 w = c_hi - c_lo;
    if (w.y > w[axis]) axis = 1;
    if (w.z > w[axis]) axis = 2;
    middle = (begin + end) / 2;
    std::nth_element(entries.begin() + begin, entries.begin() + middle, entries.begin() + end,
                     [axis](const Entry& a, const Entry& b) { return a.bounds.centre()[axis] < b.bounds.centre()[axis]; });
  }
  if (middle == begin || middle == end) middle = (begin + end) / 2;
  build(entries, begin, middle, index, depth + 1);
  const uint32_t second = build(entries, middle, end, index, depth + 1);
  nodes_[index].second = second;
  nodes_[index].cluster = LightCluster::from(all);
  const LightCluster &a = nodes_[index + 1].cluster, &b = nodes_[second].cluster;
  if (a.centre == b.centre && a.r2 == b.r2 && a.axis == b.axis && a.cos_o == b.cos_o && a.sin_o == b.sin_o &&
      a.cos_e == b.cos_e && a.phi > 0.0f && b.phi > 0.0f)
    nodes_[index].split = a.phi / (a.phi + b.phi);
  return index;
}

float LightTree::first_child_probability(const Node& node, const LightSampleContext& ctx, bool* reachable) const {
  *reachable = true;
  if (node.split >= 0.0f) return node.split;
  const Node* first = &node + 1;
  const float i0 = first->cluster.importance(ctx.p, ctx.n);
  const float i1 = nodes_[node.second].cluster.importance(ctx.p, ctx.n);
  *reachable = i0 + i1 > 0.0f;
  return *reachable ? i0 / (i0 + i1) : 0.0f;
}

float LightTree::infinite_share(const LightSampleContext& ctx) const {
  if (infinite_.empty()) return 0.0f;
  if (nodes_.empty()) return 1.0f;
  const double e_tree = static_cast<double>(nodes_[0].cluster.importance(ctx.p, ctx.n)) * phi_total_;
  if (!(e_tree > 0.0)) return 1.0f;  // no finite light reaches the point
  const double share = infinite_total_ / (infinite_total_ + e_tree);
  return std::clamp(static_cast<float>(share), kMinShare, 1.0f - kMinShare);
}

const Light* LightTree::sample(const LightSampleContext& ctx, float u, float* pmf) const {
  *pmf = 0.0f;
  const float p_inf = infinite_share(ctx);
  if (u < p_inf) {
    u /= p_inf;
    // Among the infinite lights by irradiance (a short list).
    float target = u * static_cast<float>(infinite_total_);
    for (size_t i = 0; i < infinite_.size(); ++i) {
      if (target < infinite_phi_[i] || i + 1 == infinite_.size()) {
        *pmf = p_inf * static_cast<float>(infinite_phi_[i] / infinite_total_);
        return lights_[infinite_[i]];
      }
      target -= infinite_phi_[i];
    }
  }
  if (nodes_.empty()) return nullptr;
  u = std::min((u - p_inf) / (1.0f - p_inf), kOneMinusEpsilon);
  float p = 1.0f - p_inf;
  uint32_t node = 0;
  while (nodes_[node].second != 0) {
    bool reachable;
    const float p0 = first_child_probability(nodes_[node], ctx, &reachable);
    if (!reachable) return nullptr;  // no light below reaches the point
    if (u < p0) {
      u = std::min(u / p0, kOneMinusEpsilon);
      p *= p0;
      node = node + 1;
    } else {
      u = std::min((u - p0) / (1.0f - p0), kOneMinusEpsilon);
      p *= 1.0f - p0;
      node = nodes_[node].second;
    }
  }
  if (!(p > 0.0f)) return nullptr;
  *pmf = p;
  return lights_[nodes_[node].light];
}

float LightTree::pmf(const LightSampleContext& ctx, const Light* light) const {
  if (light->index >= lights_.size() || lights_[light->index] != light) return 0.0f;
  const uint32_t leaf = leaf_of_[light->index];
  if (leaf == kNone) {
    for (size_t i = 0; i < infinite_.size(); ++i)
      if (infinite_[i] == light->index)
        return infinite_share(ctx) * static_cast<float>(infinite_phi_[i] / infinite_total_);
    return 0.0f;
  }
  float p = 1.0f - infinite_share(ctx);
  for (uint32_t node = leaf; parent_[node] != kNone; node = parent_[node]) {
    const uint32_t parent = parent_[node];
    bool reachable;
    const float p0 = first_child_probability(nodes_[parent], ctx, &reachable);
    if (!reachable) return 0.0f;
    p *= node == parent + 1 ? p0 : 1.0f - p0;
  }
  return p;
}

}  // namespace kozu
