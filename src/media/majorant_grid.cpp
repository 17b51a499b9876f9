// MajorantGrid construction: per-cell maxima of density and of ρ λmax(S) over the voxels whose trilinear
// support reaches the cell (majorant_grid.h explains the bound).
#include "media/majorant_grid.h"

#include <fmt/format.h>
#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace kozu {

namespace {
// Absorbs float rounding in the interpolation and in the eigenvalue of S, so the bound holds as computed.
constexpr float kRoundingMargin = 1.0f + 1e-4f;
}  // namespace

MajorantGrid::MajorantGrid(const VoxelGrid& grid, float scale, int voxels_per_cell, int max_cells_per_axis)
    : lo_(grid.lo()), hi_(grid.hi()) {
  if (grid.empty()) throw std::invalid_argument("MajorantGrid: the voxel grid is empty");
  if (!(scale >= 0.0f) || !std::isfinite(scale))
    throw std::invalid_argument(fmt::format("MajorantGrid: invalid scale {}", scale));
  if (voxels_per_cell < 1 || max_cells_per_axis < 1)
    throw std::invalid_argument("MajorantGrid: voxels_per_cell and max_cells_per_axis must be at least 1");
  const Vec3i n = grid.resolution();
  for (int a = 0; a < 3; ++a) res_[a] = std::min((n[a] + voxels_per_cell - 1) / voxels_per_cell, max_cells_per_axis);
  cells_per_unit_ = Vec3(res_) / (hi_ - lo_);

  // ρ_i λmax(S_i) per voxel, once (0 for empty voxels: density weighting gives them no say in S(p)).
  std::vector<float> rho_lambda;
  if (grid.has_sggx()) {
    rho_lambda.resize(grid.voxel_count());
    tbb::parallel_for(size_t{0}, grid.voxel_count(), [&](size_t idx) {
      const float d = grid.density_at(idx);
      const float sigma = d > 0.0f ? sggx::max_projected_area(grid.sggx_at(idx)) : 0.0f;
      rho_lambda[idx] = d * sigma * sigma;
    });
  }

  // Voxel range of cell c on an axis: the voxels overlapping [c n / m, (c + 1) n / m], grown by one.
  const auto voxel_range = [&](int a, int c) {
    const long long num_lo = static_cast<long long>(c) * n[a], num_hi = static_cast<long long>(c + 1) * n[a];
    const int first = static_cast<int>(num_lo / res_[a]);                     // floor
    const int last = static_cast<int>((num_hi + res_[a] - 1) / res_[a]) - 1;  // ceil - 1
    return std::pair<int, int>(std::max(first - 1, 0), std::min(last + 1, n[a] - 1));
  };

  values_.assign(size_t(res_.x) * size_t(res_.y) * size_t(res_.z), 0.0f);
  tbb::parallel_for(0, res_.z, [&](int k) {
    const auto [k0, k1] = voxel_range(2, k);
    for (int j = 0; j < res_.y; ++j) {
      const auto [j0, j1] = voxel_range(1, j);
      for (int i = 0; i < res_.x; ++i) {
        const auto [i0, i1] = voxel_range(0, i);
        float dmax = 0.0f, rlmax = 0.0f;
        for (int vk = k0; vk <= k1; ++vk)
          for (int vj = j0; vj <= j1; ++vj)
            for (int vi = i0; vi <= i1; ++vi) {
              const size_t idx = grid.index(vi, vj, vk);
              dmax = std::max(dmax, grid.density_at(idx));
              if (!rho_lambda.empty()) rlmax = std::max(rlmax, rho_lambda[idx]);
            }
        values_[index(i, j, k)] = kRoundingMargin * scale * (rho_lambda.empty() ? dmax : std::sqrt(dmax * rlmax));
      }
    }
  });
  for (float v : values_) max_ = std::max(max_, v);
}

}  // namespace kozu
