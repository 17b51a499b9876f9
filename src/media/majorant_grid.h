// MajorantGrid: a coarse grid of upper bounds of a VoxelGrid's extinction over its box, walked along a ray with
// the 3D DDA of Amanatides & Woo 1987 ("A Fast Voxel Traversal Algorithm for Ray Tracing"), for delta and ratio
// tracking with piecewise-constant majorants.
//
// Cells (dual). The trilinear lookup (voxel_grid.h) is multilinear between voxel centres, so cells are laid out
// on the voxel centres: on an axis of n voxels, cell c spans voxel coordinates [c k − 1/2, (c + 1) k − 1/2] (k =
// voxels_per_cell), the first starting half a voxel before the box, m = ceil((n + 1/2) / k) of them (k grows while
// m would exceed max_cells_per_axis). Every lookup in cell c then reads only the k + 1 voxels c k − 1 … (c + 1) k − 1
// on that axis (clamped to the grid, as the lookup clamps): 2³ voxels for k = 1, against 4³ when cells of 2
// voxels tiled the box and had to be grown by one voxel for the stencil. Small cells because the expensive part of
// tracking is the lookup at each tentative collision; on the voxelized bush (thin leaves; docs/volumes.md) 8-voxel
// primal cells gave 109 tentative collisions per path, 2-voxel ones 74, dual 1-voxel ones 48. A point that rounding
// puts just outside its cell gives the next voxel a weight of that rounding's size (about 1e-6 of a voxel), which
// the 1e-4 margin below covers unless that voxel is some hundred times denser than the cell's bound.
//
// Bound. For an SGGX grid the extinction at p towards ω is scale * ρ(p) σ(ω) with σ(ω) = sqrt(ωᵀ S(p) ω) (seed
// eq. 2, 11). With the trilinear weights w_i, ρ(p) = Σ w_i ρ_i and the density-weighted S(p) = Σ w_i ρ_i S_i / ρ(p)
// (voxel_grid.h), (ρ(p) σ(ω))² = ρ(p) Σ w_i ρ_i ωᵀ S_i ω <= max_i ρ_i * max_i ρ_i ωᵀ S_i ω over the cell's voxels
// i, and ωᵀ S_i ω is bounded two ways:
//   isotropic    ωᵀ S_i ω <= λmax(S_i): the cell stores scale * sqrt(max_i ρ_i * max_i ρ_i λmax(S_i));
//   directional  ωᵀ S_i ω <= Σ_ab |S_i,ab| |ω_a| |ω_b|, so max_i ρ_i ωᵀ S_i ω <= Σ_ab E_ab |ω_a| |ω_b| with
//                E_ab = max_i ρ_i |S_i,ab| (six per cell). Exact for flakes aligned with the axes, and for a leaf
//                at 45° about 0.54 of the isotropic bound averaged over directions (against the true 1/3): the
//                bush's leaves are mostly one per cell. Stored as six bytes per cell, E_ab / max_i ρ_i λmax(S_i)
//                rounded up to 1/255 (E_ab <= ρ_i λmax(S_i), a coefficient of a PSD matrix is at most λmax).
// A ray's majorant in a cell is the smaller: isotropic * min(1, sqrt(Σ w_ab q_ab / 255)), with the six weights w
// of its direction computed once per traversal. Both bound the product of maxima, not the maximum of the per-voxel
// products ρ_i σ_i(ω): interpolation mixes one voxel's density with another voxel's S (ρ = 1 with a thin S next to
// ρ = ε with a large S exceeds both products as ε → 0). Without SGGX a cell stores scale * max_i ρ_i. Every
// value is raised by a relative 1e-4 to absorb float rounding in the interpolation and in the eigenvalue. Outside
// the cells' box the majorant is 0.
//
// Traversal. traverse(o, d, t0, t1, segment) walks the ray o + t d (local space, d need not be unit length)
// and calls segment(ta, tb, majorant) for consecutive intervals that tile [t0, t1] exactly, in order: one per
// non-empty cell crossed, and one with majorant 0 for each run of empty cells between them (and before and after
// the cells' box), which the caller skips. Each tb equals the next ta bit for bit, the first ta is t0 and the last
// tb is t1. segment may return bool (false stops the walk) or void. Rays parallel to an axis, starting inside or
// outside the box, or with d = 0 are handled; t1 may be infinite; nothing is called when t0 >= t1 or an input is
// NaN.
//
// Empty space and memory order. The walk is the cost of tracking a sparse grid: on the bush at 128 a ray crosses
// hundreds of cells, most of them empty, and the per-cell walk took half of a render's time, mostly waiting on
// cache misses. So the cells are stored in blocks of kBlock³ = 64, each with its largest bound (0: empty) as a
// float and its cells' isotropic bounds as one byte each, a cache line: code c > 0 stands for the block's largest
// times 2^((c − 255) / 16), rounded up (a bound at most 4.4 % above the float one; below 2^-15.9 of the block's
// largest it is raised to that), and code 0 for no matter. The walk steps through the blocks (a two-level
// Amanatides & Woo walk) and walks cells only inside the occupied ones.
#pragma once

#include "core/math.h"
#include "media/voxel_grid.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>
#include <vector>

namespace kozu {

class MajorantGrid {
 public:
  MajorantGrid() = default;
  // Throws std::invalid_argument for an empty grid, a negative or non-finite scale, or cell parameters < 1.
  MajorantGrid(const VoxelGrid& grid, float scale, int voxels_per_cell = 1, int max_cells_per_axis = 160);

  const Vec3i& resolution() const { return res_; }
  const Vec3& lo() const { return lo_; }
  const Vec3& hi() const { return hi_; }
  // The isotropic bound of cell (i, j, k), and its bound along the direction d (non-zero).
  float majorant(int i, int j, int k) const { return iso(index(i, j, k)); }
  float majorant(int i, int j, int k, const Vec3& d) const { return value(index(i, j, k), weights(d)); }
  float max_majorant() const { return max_; }
  bool empty() const { return codes_.empty(); }  // default-constructed
  size_t memory_bytes() const {
    return codes_.size() + directional_.size() * sizeof(Quantized) + block_max_.size() * sizeof(float);
  }

  template <class F>
  void traverse(const Vec3& o, const Vec3& d, float t0, float t1, F&& segment) const;

  // Cells per block axis for empty-space skipping (header); grids of at most this many cells per axis have none.
  static constexpr int kBlock = 4;

 private:
  template <class Cell>
  static bool dda(const Vec3& g, const Vec3& dg, const Vec3i& first, const Vec3i& last_cell, float tin, float tout,
                  Cell&& cell);
  // Block-major: the block, then the cell within it (x fastest in both).
  size_t index(int i, int j, int k) const {
    static_assert(kBlock == 4, "the shifts below");
    const size_t block = (static_cast<size_t>(k >> 2) * static_cast<size_t>(block_res_.y) + static_cast<size_t>(j >> 2)) *
                             static_cast<size_t>(block_res_.x) +
                         static_cast<size_t>(i >> 2);
    return (block << 6) | static_cast<size_t>(((k & 3) << 4) | ((j & 3) << 2) | (i & 3));
  }
  size_t block_index(int i, int j, int k) const {
    return (static_cast<size_t>(k) * static_cast<size_t>(block_res_.y) + static_cast<size_t>(j)) *
               static_cast<size_t>(block_res_.x) +
           static_cast<size_t>(i);
  }
  // Calls f and reports whether to go on (true for a void f).
  template <class F>
  static bool emit(F& f, float ta, float tb, float majorant) {
    if constexpr (std::is_void_v<std::invoke_result_t<F&, float, float, float>>) {
      f(ta, tb, majorant);
      return true;
    } else {
      return static_cast<bool>(f(ta, tb, majorant));
    }
  }

  using Quantized = std::array<uint8_t, 6>;  // E_ab / max ρ λmax in 255ths, rounded up: xx, yy, zz, xy, xz, yz
  using Weights = std::array<float, 6>;      // |ω_a| |ω_b| (twice for a != b) / 255
  static Weights weights(const Vec3& d) {
    const Vec3 u = glm::normalize(d);
    constexpr float s = 1.0f / 255.0f;
    return {s * u.x * u.x,
            s * u.y * u.y,
            s * u.z * u.z,
            2.0f * s * std::abs(u.x * u.y),
            2.0f * s * std::abs(u.x * u.z),
            2.0f * s * std::abs(u.y * u.z)};
  }
  float value(size_t cell, const Weights& w) const {
    const float bound = iso(cell);
    if (bound == 0.0f || directional_.empty()) return bound;
    const Quantized& q = directional_[cell];
    const float f = w[0] * q[0] + w[1] * q[1] + w[2] * q[2] + w[3] * q[3] + w[4] * q[4] + w[5] * q[5];
    return f < 1.0f ? bound * std::sqrt(f) : bound;
  }

  Vec3i res_{0};
  Vec3 lo_{0.0f}, hi_{0.0f};
  Vec3 cells_per_unit_{0.0f};  // res / (hi - lo)
  // The isotropic bound of a cell: its block's largest times kCodeScale[code] (code 0: no matter).
  float iso(size_t cell) const { return block_max_[cell >> 6] * kCodeScale[codes_[cell]]; }
  static const std::array<float, 256> kCodeScale;  // 0, then 2^((c − 255) / 16) for c = 1 … 255

  float max_ = 0;
  std::vector<uint8_t> codes_;     // per cell, block-major (index)
  std::vector<Quantized> directional_;  // SGGX grids only
  Vec3i block_res_{0};
  std::vector<float> block_max_;  // per block of kBlock³ cells (block_index): its largest bound, 0 if empty
};

// Amanatides & Woo over the cells first..last (inclusive; cell (i, j, k) is [i, i+1] x [j, j+1] x [k, k+1] in the
// coordinates of g, dg, the ray), from tin to tout (inside those cells' box, clipped by the caller): cell(ta, tb,
// i, j, k) per cell crossed, tiling [tin, tout] exactly; cell returns false to stop, and then so does dda. The
// cells are clamped to first..last, so a walk within a block never strays into a neighbour by rounding.
template <class Cell>
bool MajorantGrid::dda(const Vec3& g, const Vec3& dg, const Vec3i& first, const Vec3i& last_cell, float tin,
                       float tout, Cell&& cell) {
  int c[3], step[3];
  float t_next[3], t_delta[3];
  const Vec3 p = g + dg * tin;
  for (int a = 0; a < 3; ++a) {
    c[a] = std::clamp(static_cast<int>(std::floor(p[a])), first[a], last_cell[a]);
    if (dg[a] > 0.0f) {
      step[a] = 1;
      t_next[a] = (static_cast<float>(c[a] + 1) - g[a]) / dg[a];
      t_delta[a] = 1.0f / dg[a];
    } else if (dg[a] < 0.0f) {
      step[a] = -1;
      t_next[a] = (static_cast<float>(c[a]) - g[a]) / dg[a];
      t_delta[a] = -1.0f / dg[a];
    } else {
      step[a] = 0;
      t_next[a] = kInfinity;
      t_delta[a] = kInfinity;
    }
  }
  float ta = tin;
  while (true) {
    const int a = t_next[0] < t_next[1] ? (t_next[0] < t_next[2] ? 0 : 2) : (t_next[1] < t_next[2] ? 1 : 2);
    const int next = c[a] + step[a];
    // The last cell takes the rest of the interval, so rounding can neither leave a gap nor overshoot.
    const bool last = !(t_next[a] < tout) || next < first[a] || next > last_cell[a];
    const float tb = last ? tout : std::max(t_next[a], ta);
    if (!cell(ta, tb, c[0], c[1], c[2])) return false;
    if (last) return true;
    ta = tb;
    c[a] = next;
    t_next[a] += t_delta[a];
  }
}

// Slab clipping of [t0, t1] against the box [lo, hi] (cell coordinates); false if the ray misses it.
inline bool clip_to_cells(const Vec3& g, const Vec3& dg, const Vec3i& lo, const Vec3i& hi, float t0, float t1,
                          float* tin, float* tout) {
  *tin = t0;
  *tout = t1;
  for (int a = 0; a < 3; ++a) {
    if (dg[a] == 0.0f) {
      if (g[a] < static_cast<float>(lo[a]) || g[a] > static_cast<float>(hi[a])) return false;  // parallel, outside
      continue;
    }
    const float inv = 1.0f / dg[a];
    float ta = (static_cast<float>(lo[a]) - g[a]) * inv, tb = (static_cast<float>(hi[a]) - g[a]) * inv;
    if (ta > tb) std::swap(ta, tb);
    *tin = std::max(*tin, ta);
    *tout = std::min(*tout, tb);
  }
  return *tin < *tout;
}

template <class F>
void MajorantGrid::traverse(const Vec3& o, const Vec3& d, float t0, float t1, F&& segment) const {
  if (!(t0 < t1) || !is_finite(o) || !is_finite(d) || std::isnan(t0) || std::isnan(t1) || codes_.empty()) return;
  const Weights w = directional_.empty() ? Weights{} : weights(d);
  // Runs of empty cells (and of empty blocks) become one segment: the caller skips them anyway, and most of a
  // sparse grid's cells are empty.
  float empty_from = t0;  // where the pending empty run started
  bool go_on = true;
  const auto cell = [&](float ta, float tb, float majorant) {
    if (majorant == 0.0f) return true;
    if (empty_from < ta && !emit(segment, empty_from, ta, 0.0f)) return go_on = false;
    empty_from = tb;
    return go_on = emit(segment, ta, tb, majorant);
  };
  // The ray in cell coordinates: the cells' box is [0, res], cell (i, j, k) is [i, i+1] x [j, j+1] x [k, k+1].
  const Vec3 g = (o - lo_) * cells_per_unit_;
  const Vec3 dg = d * cells_per_unit_;
  // The cells first..last cell by cell over [ta, tb] (a block's interval, or the ray) within the grid.
  const auto walk_cells = [&](const Vec3i& first, const Vec3i& last, float ta, float tb) {
    float tin, tout;
    // Clipped to the whole grid (not the block: its faces, computed again, would leave slivers of a cell unwalked).
    if (!clip_to_cells(g, dg, Vec3i(0), res_, ta, tb, &tin, &tout)) return true;
    return dda(g, dg, first, last, tin, tout, [&](float a, float b, int i, int j, int k) {
      return cell(a, b, value(index(i, j, k), w));
    });
  };
  // Blocks of kBlock³ cells: a block without matter is crossed in one step, the others cell by cell, their walk
  // clamped to the block's cells.
  const Vec3 gb = g * (1.0f / kBlock), dgb = dg * (1.0f / kBlock);
  float tin, tout;
  if (clip_to_cells(gb, dgb, Vec3i(0), block_res_, t0, t1, &tin, &tout))
    dda(gb, dgb, Vec3i(0), block_res_ - 1, tin, tout, [&](float a, float b, int i, int j, int k) {
      const size_t block = block_index(i, j, k);
      if (block_max_[block] == 0.0f) return true;
      // Its bounds, fetched together rather than one miss per cell as the walk reaches them.
      __builtin_prefetch(&codes_[block << 6]);
      if (!directional_.empty())  // 64 cells of sizeof(Quantized) bytes: that many 64-byte lines
        for (size_t line = 0; line < sizeof(Quantized); ++line)
          __builtin_prefetch(reinterpret_cast<const char*>(&directional_[block << 6]) + 64 * line);
      const Vec3i first = Vec3i(i, j, k) * kBlock;
      return walk_cells(first, glm::min(first + (kBlock - 1), res_ - 1), a, b) && go_on;
    });
  if (go_on && empty_from < t1) emit(segment, empty_from, t1, 0.0f);
}

}  // namespace kozu
