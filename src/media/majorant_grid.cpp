// MajorantGrid construction: per-cell maxima of density and of ρ λmax(S) over the voxels whose trilinear
// support reaches the cell (majorant_grid.h explains the bound).
#include "media/majorant_grid.h"

#include <fmt/format.h>
#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace kozu {

namespace {
// Absorbs float rounding in the interpolation and in the eigenvalue of S, so the bound holds as computed.
constexpr float kRoundingMargin = 1.0f + 1e-4f;
}  // namespace

MajorantGrid::MajorantGrid(const VoxelGrid& grid, float scale, int voxels_per_cell, int max_cells_per_axis) {
  if (grid.empty()) throw std::invalid_argument("MajorantGrid: the voxel grid is empty");
  if (!(scale >= 0.0f) || !std::isfinite(scale))
    throw std::invalid_argument(fmt::format("MajorantGrid: invalid scale {}", scale));
  if (voxels_per_cell < 1 || max_cells_per_axis < 1)
    throw std::invalid_argument("MajorantGrid: voxels_per_cell and max_cells_per_axis must be at least 1");
  const Vec3i n = grid.resolution();
  const Vec3 voxel = grid.voxel_size();
  // Dual cells (header): k voxels wide, the first starting half a voxel before the box, enough of them to cover it.
  Vec3i k;
  for (int a = 0; a < 3; ++a) {
    k[a] = voxels_per_cell;
    const auto cells = [&] { return (2 * n[a] + 1 + 2 * k[a] - 1) / (2 * k[a]); };  // ceil((n + 1/2) / k)
    while (cells() > max_cells_per_axis) ++k[a];
    res_[a] = cells();
  }
  lo_ = grid.lo() - 0.5f * voxel;
  hi_ = lo_ + Vec3(res_ * k) * voxel;
  cells_per_unit_ = Vec3(res_) / (hi_ - lo_);

  for (int a = 0; a < 3; ++a) block_res_[a] = (res_[a] + kBlock - 1) / kBlock;
  const size_t blocks = size_t(block_res_.x) * size_t(block_res_.y) * size_t(block_res_.z);
  // The float bounds while building; the blocks past the grid's edge stay 0.
  std::vector<float> values(blocks * kBlock * kBlock * kBlock, 0.0f);

  const bool sggx = grid.has_sggx();
  if (sggx) directional_.assign(values.size(), Quantized{});

  // Cell c on an axis spans voxel coordinates [c k - 1/2, (c + 1) k - 1/2], between the centres of voxels c k - 1 and
  // (c + 1) k - 1: those k + 1 voxels (clamped to the grid, as the lookup clamps) are all its trilinear stencils use.
  const auto voxel_range = [&](int a, int c) {
    return std::pair<int, int>(std::clamp(c * k[a] - 1, 0, n[a] - 1), std::clamp((c + 1) * k[a] - 1, 0, n[a] - 1));
  };

  // Per voxel, once: ρ, ρ λmax(S) and ρ |S| per coefficient (0 for empty voxels: density weighting gives them no
  // say in S(p)), for the z slices the current layer of cells reads; a slice is freed once no later layer reads it,
  // so this takes a few slices' memory, not the grid's.
  struct Voxel {
    float rho = 0, rho_lambda = 0;
    std::array<float, 6> rho_abs_s{};
  };
  const size_t slice_size = size_t(n.x) * size_t(n.y);
  std::vector<std::vector<Voxel>> slices(size_t(n.z));
  const auto slice = [&](int z) -> const std::vector<Voxel>& {
    std::vector<Voxel>& v = slices[size_t(z)];
    if (v.empty()) {
      v.resize(slice_size);
      tbb::parallel_for(size_t{0}, slice_size, [&](size_t xy) {
        const size_t idx = size_t(z) * slice_size + xy;
        Voxel& out = v[xy];
        out.rho = grid.density_at(idx);
        if (!sggx || !(out.rho > 0.0f)) return;
        const Sggx S = grid.sggx_at(idx);
        const float sigma = sggx::max_projected_area(S);
        out.rho_lambda = out.rho * sigma * sigma;
        out.rho_abs_s = {out.rho * S.xx,           out.rho * S.yy,           out.rho * S.zz,
                         out.rho * std::abs(S.xy), out.rho * std::abs(S.xz), out.rho * std::abs(S.yz)};
      });
    }
    return v;
  };

  for (int kz = 0; kz < res_.z; ++kz) {
    const auto [k0, k1] = voxel_range(2, kz);
    for (int z = 0; z < k0; ++z) std::vector<Voxel>().swap(slices[size_t(z)]);
    for (int z = k0; z <= k1; ++z) slice(z);
    tbb::parallel_for(0, res_.y, [&, k0 = k0, k1 = k1](int j) {
      const auto [j0, j1] = voxel_range(1, j);
      for (int i = 0; i < res_.x; ++i) {
        const auto [i0, i1] = voxel_range(0, i);
        float dmax = 0.0f, rlmax = 0.0f;
        std::array<float, 6> smax{};
        for (int vk = k0; vk <= k1; ++vk) {
          const std::vector<Voxel>& sl = slices[size_t(vk)];
          for (int vj = j0; vj <= j1; ++vj)
            for (int vi = i0; vi <= i1; ++vi) {
              const Voxel& v = sl[size_t(vj) * size_t(n.x) + size_t(vi)];
              dmax = std::max(dmax, v.rho);
              rlmax = std::max(rlmax, v.rho_lambda);
              for (int c = 0; c < 6; ++c) smax[c] = std::max(smax[c], v.rho_abs_s[c]);
            }
        }
        values[index(i, j, kz)] = kRoundingMargin * scale * (sggx ? std::sqrt(dmax * rlmax) : dmax);
        if (!directional_.empty() && rlmax > 0.0f) {
          Quantized& q = directional_[index(i, j, kz)];
          for (int c = 0; c < 6; ++c)  // rounded up, so the bound holds; E_ab <= max ρ λmax
            q[c] = static_cast<uint8_t>(std::min(255.0f, std::ceil(255.0f * (smax[c] / rlmax) * kRoundingMargin)));
        }
      }
    });
  }
  // Per block its largest bound, per cell a byte (header): the smallest code whose value is not below the bound.
  constexpr size_t kCells = kBlock * kBlock * kBlock;
  block_max_.assign(blocks, 0.0f);
  codes_.assign(values.size(), 0);
  tbb::parallel_for(size_t{0}, blocks, [&](size_t b) {
    float m = 0.0f;
    for (size_t c = b * kCells; c < (b + 1) * kCells; ++c) m = std::max(m, values[c]);
    block_max_[b] = m;
    for (size_t c = b * kCells; c < (b + 1) * kCells; ++c) {
      if (!(values[c] > 0.0f)) continue;
      int code = std::clamp(255 + static_cast<int>(std::ceil(16.0f * std::log2(values[c] / m))), 1, 255);
      while (code < 255 && m * kCodeScale[size_t(code)] < values[c]) ++code;  // rounding of log2 and the product
      codes_[c] = static_cast<uint8_t>(code);
    }
  });
  for (float v : block_max_) max_ = std::max(max_, v);
}

const std::array<float, 256> MajorantGrid::kCodeScale = [] {
  std::array<float, 256> t{};
  for (int c = 1; c < 256; ++c) t[size_t(c)] = std::exp2(static_cast<float>(c - 255) / 16.0f);
  t[255] = 1.0f;
  return t;
}();

}  // namespace kozu
