#include "integrators/directional_quadtree.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>

namespace kozu {

namespace {
constexpr double kFixedScale = 1048576.0;  // 2^20 record units per unit of Li/p
constexpr float kMaxRecord = 1e6f;         // a record's cap: 2^64 units hold 1.7e7 records at the cap
constexpr double kBelowOne = 0.99999994;   // the largest float below 1
}  // namespace

Vec2 DirectionalQuadtree::to_square(const Vec3& d) {
  const float x = std::clamp((d.z + 1.0f) * 0.5f, 0.0f, float(kBelowOne));
  float phi = fast_atan2(d.y, d.x);  // std::atan2f was 23 of a density's 77 ns (docs/performance.md)
  if (phi < 0.0f) phi += 2.0f * kPi;
  const float y = std::clamp(phi * (0.5f * kInvPi), 0.0f, float(kBelowOne));
  return Vec2(x, y);
}

Vec3 DirectionalQuadtree::to_direction(const Vec2& p) {
  const float cos_theta = 2.0f * p.x - 1.0f;
  const float sin_theta = std::sqrt(std::max(0.0f, 1.0f - cos_theta * cos_theta));
  const float phi = 2.0f * kPi * p.y;
  return Vec3(sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta);
}

namespace {
// One binary choice of the descent: the lower half with probability `lower`, u rescaled into the half it chose.
int choose_half(float& u, float lower) {
  const int upper = u >= lower;
  u = upper ? (u - lower) / (1.0f - lower) : u / lower;
  u = std::clamp(u, 0.0f, float(kBelowOne));
  return upper;
}
}  // namespace

// §3.3: descend by the quadrants' probabilities, one half in x, then one in y given x, reusing u.
Vec3 DirectionalQuadtree::sample(const Vec2& u, float* pdf_out) const {
  float x = std::min(u.x, float(kBelowOne)), y = std::min(u.y, float(kBelowOne));
  float origin_x = 0.0f, origin_y = 0.0f, size = 1.0f, density = 1.0f;
  uint32_t n = 0;
  for (;;) {
    const Node& node = nodes_[n];
    const std::array<float, 4>& p = node.p;
    const int qx = choose_half(x, p[0] + p[2]);
    const int qy = choose_half(y, p[qx] / (p[qx] + p[qx + 2]));
    const int q = qx + 2 * qy;
    density *= 4.0f * p[q];
    size *= 0.5f;
    origin_x += float(qx) * size;
    origin_y += float(qy) * size;
    if (node.child[q] == 0) break;
    n = node.child[q];
  }
  *pdf_out = density * (0.25f * kInvPi);  // the square's area 1 is the sphere's 4π
  return to_direction(Vec2(origin_x + x * size, origin_y + y * size));
}

// The cell path of a point in 32-bit fixed point: level l's quadrant is bit 31 − l of x and of y, so the descent
// does no float arithmetic (which, level after level, was one long dependency chain).
namespace {
struct FixedPoint {
  uint32_t x, y;
  explicit FixedPoint(const Vec2& p)
      : x(uint32_t(std::min(double(p.x), kBelowOne) * 4294967296.0)),
        y(uint32_t(std::min(double(p.y), kBelowOne) * 4294967296.0)) {}
  int quadrant(int level) const { return int((x >> (31 - level)) & 1u) | int(((y >> (31 - level)) & 1u) << 1); }
};
}  // namespace

float DirectionalQuadtree::pdf(const Vec3& d) const {
  if (empty_) return 0.0f;
  const FixedPoint s(to_square(d));
  float density = 0.25f * kInvPi;
  uint32_t n = 0;
  for (int level = 0;; ++level) {
    const Node& node = nodes_[n];
    const int q = s.quadrant(level);
    density *= 4.0f * node.p[q];
    if (node.child[q] == 0) return density;
    n = node.child[q];
  }
}

void DirectionalQuadtree::record(const Vec3& d, float value, uint32_t dither) const {
  if (!(value > 0.0f)) return;  // also NaN
  const FixedPoint s(to_square(d));
  uint32_t n = 0;
  for (int level = 0;; ++level) {
    const int q = s.quadrant(level);
    const Node& node = nodes_[n];
    if (node.child[q] == 0) {
      // Stochastic rounding: the expected units are exactly value · 2^20.
      const double units = double(std::min(value, kMaxRecord)) * kFixedScale;
      const double whole = std::floor(units);
      const uint64_t add = uint64_t(whole) + (dither * (1.0 / 4294967296.0) < units - whole ? 1u : 0u);
      if (add) std::atomic_ref<uint64_t>(records_[n][q]).fetch_add(add, std::memory_order_relaxed);
      return;
    }
    n = node.child[q];
  }
}

double DirectionalQuadtree::subtree_records(uint32_t n, std::vector<double>& totals) const {
  double total = 0.0;
  for (int q = 0; q < 4; ++q) {
    const uint32_t c = nodes_[n].child[q];
    const double e = c ? subtree_records(c, totals) : double(records_[n][q]);
    totals[4 * n + q] = e;
    total += e;
  }
  return total;
}

// §4.2: a quadrant keeps children (or gets them) while its share of the energy exceeds ρ; below, it is one leaf. A
// quadrant that was a leaf and is subdivided gives each child a quarter of its energy (its records cannot say more).
// Each node keeps its quadrants' shares of its own energy, the probabilities sampling descends by.
DirectionalQuadtree DirectionalQuadtree::refined() const {
  std::vector<double> totals(4 * nodes_.size());
  const double total = subtree_records(0, totals);
  DirectionalQuadtree out;
  if (!(total > 0.0)) {
    out = *this;
    for (auto& r : out.records_) r = {};
    return out;
  }
  out.nodes_.clear();
  out.nodes_.emplace_back();
  constexpr int64_t kNone = -1;
  std::function<void(uint32_t, int64_t, const std::array<double, 4>&, int)> build =
      [&](uint32_t at, int64_t old, const std::array<double, 4>& energy, int depth) {
        const double node_energy = energy[0] + energy[1] + energy[2] + energy[3];
        for (int q = 0; q < 4; ++q) {
          out.nodes_[at].p[q] = float(energy[q] / node_energy);
          if (!(energy[q] / total > kSubdivideShare) || depth >= kMaxDepth) continue;
          const uint32_t old_child = old != kNone ? nodes_[size_t(old)].child[q] : 0;
          std::array<double, 4> child_energy;
          if (old_child)
            for (int k = 0; k < 4; ++k) child_energy[k] = totals[4 * old_child + k];
          else
            child_energy.fill(energy[q] * 0.25);
          const uint32_t c = uint32_t(out.nodes_.size());
          out.nodes_.emplace_back();
          out.nodes_[at].child[q] = c;
          build(c, old_child ? int64_t(old_child) : kNone, child_energy, depth + 1);
        }
      };
  build(0, 0, {totals[0], totals[1], totals[2], totals[3]}, 1);
  out.records_.assign(out.nodes_.size(), {});
  out.empty_ = false;
  return out;
}

int DirectionalQuadtree::depth() const {
  std::function<int(uint32_t)> d = [&](uint32_t n) {
    int deepest = 0;
    for (uint32_t c : nodes_[n].child)
      if (c) deepest = std::max(deepest, d(c));
    return deepest + 1;
  };
  return d(0);
}

}  // namespace kozu
