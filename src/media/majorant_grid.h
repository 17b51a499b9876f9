// MajorantGrid: a coarse grid of upper bounds of a VoxelGrid's extinction over its box, walked along a ray with
// the 3D DDA of Amanatides & Woo 1987 ("A Fast Voxel Traversal Algorithm for Ray Tracing"), for delta and ratio
// tracking with piecewise-constant majorants.
//
// Cells. cells per axis = min(ceil(n / voxels_per_cell), max_cells_per_axis) for a VoxelGrid of n voxels on that
// axis (defaults 2 and 128: one cell per 2^3 voxels, at most 128^3 cells, 8 MiB; a 128^3 grid gets 64^3 cells,
// 1 MiB, against its 56 MiB of SGGX voxels). Small cells because the expensive part of tracking is the lookup at
// each tentative collision: on the voxelized bush (thin leaves) 8-voxel cells gave 109 tentative collisions
// per path, 57 % of them in empty voxels, and 2-voxel cells rendered 1.9x faster (docs/volumes.md). The cells
// tile the same box [lo, hi] as the voxels, with cell c on an axis covering voxel-space [c n / m, (c + 1) n / m].
//
// Bound. For an SGGX grid the extinction at p towards ω is scale * ρ(p) σ(ω) with σ(ω) = sqrt(ωᵀ S(p) ω) (seed
// eq. 2, 11). With the trilinear weights w_i, ρ(p) = Σ w_i ρ_i and the density-weighted S(p) = Σ w_i ρ_i S_i / ρ(p)
// (voxel_grid.h), (ρ(p) σ(ω))² = ρ(p) Σ w_i ρ_i ωᵀ S_i ω <= max_i ρ_i * max_i ρ_i λmax(S_i), so a cell stores
//     scale * sqrt(max_i ρ_i * max_i ρ_i λmax(S_i))
// over the voxels i whose trilinear support can reach the cell: the voxels overlapping the cell, grown by one on
// every side (clamped to the grid). This is at most scale * max ρ_i * max sqrt(λmax(S_i)) and, unlike the
// maximum of the per-voxel products ρ_i sqrt(λmax(S_i)), a bound: interpolation mixes one voxel's density with
// another voxel's S (ρ = 1 with a thin S next to ρ = ε with a large S exceeds both products as ε → 0). Without
// SGGX the cell stores scale * max_i ρ_i. Every value is raised by a relative 1e-4 to absorb float rounding in
// the interpolation and in the eigenvalue. Outside the box the majorant is 0.
//
// Traversal. traverse(o, d, t0, t1, segment) walks the ray o + t d (local space, d need not be unit length)
// and calls segment(ta, tb, majorant) for consecutive intervals that tile [t0, t1] exactly, in order: the part
// before the box and the part after it (if any) as one segment each with majorant 0, then one segment per cell
// crossed. Each tb equals the next ta bit for bit, the first ta is t0 and the last tb is t1; empty cells give
// segments with majorant 0 that the caller skips. segment may return bool (false stops the walk) or void.
// Rays parallel to an axis, starting inside or outside the box, or with d = 0 are handled; t1 may be infinite;
// nothing is called when t0 >= t1 or an input is NaN.
#pragma once

#include "core/math.h"
#include "media/voxel_grid.h"

#include <cstddef>
#include <type_traits>
#include <utility>
#include <vector>

namespace kozu {

class MajorantGrid {
 public:
  MajorantGrid() = default;
  // Throws std::invalid_argument for an empty grid, a negative or non-finite scale, or cell parameters < 1.
  MajorantGrid(const VoxelGrid& grid, float scale, int voxels_per_cell = 2, int max_cells_per_axis = 128);

  const Vec3i& resolution() const { return res_; }
  const Vec3& lo() const { return lo_; }
  const Vec3& hi() const { return hi_; }
  float majorant(int i, int j, int k) const { return values_[index(i, j, k)]; }
  float max_majorant() const { return max_; }
  size_t memory_bytes() const { return values_.size() * sizeof(float); }

  template <class F>
  void traverse(const Vec3& o, const Vec3& d, float t0, float t1, F&& segment) const;

 private:
  size_t index(int i, int j, int k) const {
    return (static_cast<size_t>(k) * static_cast<size_t>(res_.y) + static_cast<size_t>(j)) *
               static_cast<size_t>(res_.x) +
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

  Vec3i res_{0};
  Vec3 lo_{0.0f}, hi_{0.0f};
  Vec3 cells_per_unit_{0.0f};  // res / (hi - lo)
  float max_ = 0;
  std::vector<float> values_;
};

template <class F>
void MajorantGrid::traverse(const Vec3& o, const Vec3& d, float t0, float t1, F&& segment) const {
  if (!(t0 < t1) || !is_finite(o) || !is_finite(d) || std::isnan(t0) || std::isnan(t1) || values_.empty()) return;
  // The ray in cell coordinates: the box is [0, res], cell (i, j, k) is [i, i+1] x [j, j+1] x [k, k+1].
  const Vec3 g = (o - lo_) * cells_per_unit_;
  const Vec3 dg = d * cells_per_unit_;

  // Slab clipping of [t0, t1] against the box.
  float tin = t0, tout = t1;
  for (int a = 0; a < 3; ++a) {
    if (dg[a] == 0.0f) {
      if (g[a] < 0.0f || g[a] > static_cast<float>(res_[a])) tin = kInfinity;  // parallel and outside: a miss
      continue;
    }
    const float inv = 1.0f / dg[a];
    float ta = (0.0f - g[a]) * inv, tb = (static_cast<float>(res_[a]) - g[a]) * inv;
    if (ta > tb) std::swap(ta, tb);
    tin = std::max(tin, ta);
    tout = std::min(tout, tb);
  }
  if (!(tin < tout)) {  // misses the box: one empty segment
    emit(segment, t0, t1, 0.0f);
    return;
  }
  if (tin > t0 && !emit(segment, t0, tin, 0.0f)) return;

  // Amanatides & Woo: the entry cell, then per axis the step, the t of the next boundary and the t per cell.
  int cell[3], step[3];
  float t_next[3], t_delta[3];
  const Vec3 p = g + dg * tin;
  for (int a = 0; a < 3; ++a) {
    cell[a] = std::clamp(static_cast<int>(std::floor(p[a])), 0, res_[a] - 1);
    if (dg[a] > 0.0f) {
      step[a] = 1;
      t_next[a] = (static_cast<float>(cell[a] + 1) - g[a]) / dg[a];
      t_delta[a] = 1.0f / dg[a];
    } else if (dg[a] < 0.0f) {
      step[a] = -1;
      t_next[a] = (static_cast<float>(cell[a]) - g[a]) / dg[a];
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
    const int next = cell[a] + step[a];
    // The last cell takes the rest of the interval, so rounding can neither leave a gap nor overshoot.
    const bool last = !(t_next[a] < tout) || next < 0 || next >= res_[a];
    const float tb = last ? tout : std::max(t_next[a], ta);
    if (!emit(segment, ta, tb, values_[index(cell[0], cell[1], cell[2])])) return;
    if (last) break;
    ta = tb;
    cell[a] = next;
    t_next[a] += t_delta[a];
  }
  if (tout < t1) emit(segment, tout, t1, 0.0f);
}

}  // namespace kozu
