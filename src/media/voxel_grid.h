// VoxelGrid: a dense voxel grid of density and, optionally, SGGX microflake matrices S (Heitz, Dupuy, Crassin &
// Dachsbacher 2015, "The SGGX Microflake Distribution", ACM TOG 34(4), SIGGRAPH 2015), with
// trilinear lookups, a 3D MIP chain for prefiltering (§4.4 "linear prefiltering", §6 Fig. 18), and loading
// from OpenVDB (.vdb) or kozu's raw .kvox files.
//
// Geometry. The grid covers the axis-aligned box [lo, hi] of the medium's local space with (nx, ny, nz) voxels;
// voxel (i, j, k) has its centre at lo + ((i, j, k) + 0.5) * (hi - lo) / (nx, ny, nz).
//
// Interpolation (§4.4 "linear interpolation", eq. 10 and 20):
//  - density(p): trilinear over the eight nearest voxel centres, clamped to the edge voxels inside the box
//    (the outer half voxel repeats the edge value), 0 outside [lo, hi].
//  - sggx(p): the six coefficients Sxx..Syz are interpolated linearly (never the compact form of eq. 19, which is
//    not closed under convex combination). Deviation, documented: the trilinear weights are multiplied by the
//    voxels' densities (S(p) = Σ w_i ρ_i S_i / Σ w_i ρ_i), the same density weighting as the MIP chain below,
//    so that empty voxels, whose S is a meaningless placeholder, do not dilute the orientation of the flakes at
//    a surface. Where all eight densities are 0 the plain trilinear weights are used. Both are convex
//    combinations, so S(p) stays symmetric positive (semi-)definite, and with a constant density it is the
//    plain trilinear interpolation. Outside the box sggx(p) returns the clamped edge value (density is 0 there).
//
// MIP chain (build_mip_chain). Level l+1 averages 2x2x2 blocks of level l; resolution per axis
// n' = max(1, ceil(n / 2)), and on an odd axis the last block repeats the edge voxel (clamp). Density is the
// block mean. S is the density-weighted mean Σ ρ_i S_i / Σ ρ_i of the six coefficients: the paper filters S
// linearly (§4.4) because a blend of flake distributions adds the flakes' projected areas (§4.1, obs. 3), and
// the number of flakes a voxel contributes to the blend is proportional to its density; an empty block keeps
// the plain mean. Every level keeps the same box [lo, hi], so voxels grow. Seed §6 notes that downsampling
// density ignores the correlation of visibility along a path (Fig. 18), so callers may pick the density and
// S levels separately.
//
// File formats (load dispatches on the extension, case-insensitive):
//
//  .kvox (kozu's raw format), little-endian:
//     offset  size  field
//      0       8    magic "KOZUVOX1"
//      8      12    uint32 nx, ny, nz (each >= 1)
//     20       4    uint32 channel count: 1 = density, 7 = density, Sxx, Syy, Szz, Sxy, Sxz, Syz
//     24      24    float32 lo[3], hi[3] (finite, lo < hi on every axis)
//     48       -    float32 values, nx*ny*nz*channels of them, interleaved per voxel (all channels of a voxel
//                   together), voxels with x fastest, then y, then z: voxel (i, j, k) starts at value
//                   ((k * ny + j) * nx + i) * channels.
//    The file must end right after the last value. Values must be finite, densities >= 0, S diagonals >= 0 and
//    |Sxy| <= sqrt(Sxx Syy) (and likewise for xz, yz; the |r| <= 1 of eq. 19) within a relative 1e-3.
//
//  .vdb (OpenVDB 10): the float grid named "density", otherwise the first float grid in the file; level sets
//    are rejected. The grid is made dense over its active voxels' bounding box [imin, imax] (index space,
//    inclusive), inactive voxels inside taking their stored (background) value. OpenVDB puts voxel centres at
//    integer index coordinates, so with the grid's transform world = index * voxel_size + translation
//    (a per-axis scale and a translation; rotations, shears, mirrors and frustum maps are rejected):
//      lo = world(imin - 0.5), hi = world(imax + 0.5), resolution = imax - imin + 1,
//    which puts kozu's voxel (i, j, k) centre exactly at world(imin + (i, j, k)). SGGX channels are not read
//    from .vdb files.
//
//  .kvox version 2 (compact, written for compact grids; version 1 files are still read), little-endian:
//     offset  size  field
//      0       8    magic "KOZUVOX2"
//      8      40    as version 1: uint32 nx, ny, nz, uint32 channels (1 or 7), float32 lo[3], hi[3]
//     48       4    float32 density_step: a voxel's density is its 16-bit code times this (finite, >= 0)
//     52       4    float32 sigma_scale: S by eq. 20 from the 6-byte code with this scale (finite, > 0)
//     56       -    per voxel in version 1's order: uint16 density code, then with 7 channels the 6 bytes of
//                   SggxCompact (uint8 σx, σy, σz; int8 rxy, rxz, ryz), whose correlations must pass
//                   sggx::decompress's guard as stored (sggx::compress_spd writes such codes).
//
// Compact storage (compact(); seed eqs. 19–20): densities as 16-bit codes of density_step = (largest
// density) / 65535, so the error is at most half a step, 7.6e-6 of the largest, and 0 stays exactly 0; S as
// sggx::compress_spd's 6 bytes with sigma_scale = the largest sqrt(S_aa) over the voxels (errors: ≤
// sigma_scale/510 in each σ_a, ≤ 1/254 in each r, more only where the correlations had to shrink to stay
// positive definite). 2 bytes per voxel for density, 8 with S, instead of 4 and 28. Lookups decode the eight
// voxels they blend (eq. 20, no guard); sggx_extinction forms ωᵀS_iω from the codes directly. A compact grid
// is read-only: set_voxel throws std::logic_error and density_data() / sggx_data() are empty.
//
// Errors: every problem with a file (missing, unreadable, bad magic, truncated or oversized data, NaN or
// negative values, no float grid, unsupported transform, more than kMaxVoxels voxels or more memory than is
// left) throws InputError(file, "", message). A .vdb file's header, metadata and grid descriptors are checked
// against its size before OpenVDB reads it (OpenVDB trusts them).
#pragma once

#include "core/math.h"
#include "media/sggx.h"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

namespace kozu {

using Vec3i = glm::ivec3;

// Throws InputError(name, "", ...) when a float grid of n voxels (with S when sggx), its MIP chain and majorants
// would not fit in the memory left (core/memory.h): the check load() makes, for grids made in memory.
void check_voxel_grid_memory(const std::string& name, const Vec3i& n, bool sggx);

class VoxelGrid {
 public:
  // Largest grid load() accepts (2^28 voxels, e.g. 645^3: 1 GiB of density alone, 7 GiB with SGGX); a grid must
  // also fit in the memory left (core/memory.h).
  static constexpr size_t kMaxVoxels = size_t{1} << 28;

  VoxelGrid() = default;
  // All densities 0; S (when has_sggx) the isotropic default Sggx{}. Throws std::invalid_argument for a
  // resolution below 1 or an empty or non-finite box.
  VoxelGrid(const Vec3i& resolution, const Vec3& lo, const Vec3& hi, bool has_sggx);

  // Reads a .vdb or .kvox file (see the header comment). Throws InputError naming the file.
  static VoxelGrid load(const std::filesystem::path& file);
  // A .kvox file's bytes already in memory; `file` names them in messages.
  static VoxelGrid from_kvox_bytes(const std::filesystem::path& file, std::string_view data);
  // Writes the grid as .kvox (7 channels with S, else 1) through write_file_atomic. Throws std::runtime_error.
  void save_kvox(const std::filesystem::path& file) const;
  // Writes the densities as an OpenVDB float grid "density" (voxel size and origin so that load() reads the same box
  // back, zero voxels inactive), through a temporary file renamed into place: for other renderers (Blender reads it).
  // A grid with S is refused: OpenVDB files carry no SGGX. Throws std::runtime_error.
  void save_vdb(const std::filesystem::path& file) const;

  // Trilinear lookups in the medium's local space (see the header comment for the clamping and weighting).
  float density(const Vec3& p) const;
  Sggx sggx(const Vec3& p) const;
  // Both at once (one set of weights); sggx is Sggx{} when the grid has no S.
  struct Lookup {
    float density = 0;
    Sggx sggx;
  };
  Lookup lookup(const Vec3& p) const;
  // ρ(p) σ(ω) = ρ(p) sqrt(ωᵀ S(p) ω) (eqs. 2, 11) for the density-weighted S(p) above, without forming
  // S(p): with ρ(p) = Σ w_i ρ_i and S(p) = Σ w_i ρ_i S_i / ρ(p), (ρ σ)² = ρ(p) Σ w_i ρ_i ωᵀ S_i ω. Voxels with
  // ρ_i = 0 cost nothing, which is most of them in a sparse grid. 0 outside the box; requires has_sggx().
  float sggx_extinction(const Vec3& p, const Vec3& w) const;

  // Voxel access; (i, j, k) must lie in [0, resolution), idx in [0, voxel_count()). Both storages.
  size_t index(int i, int j, int k) const {
    return (static_cast<size_t>(k) * static_cast<size_t>(res_.y) + static_cast<size_t>(j)) *
               static_cast<size_t>(res_.x) +
           static_cast<size_t>(i);
  }
  float density_at(size_t idx) const { return compact_ ? float(density16_[idx]) * density_step_ : density_[idx]; }
  Sggx sggx_at(size_t idx) const {
    return compact_ ? sggx::decompress_unguarded(sggx6_[idx], sigma_scale_) : sggx_[idx];
  }
  float voxel_density(int i, int j, int k) const { return density_at(index(i, j, k)); }
  Sggx voxel_sggx(int i, int j, int k) const { return sggx_at(index(i, j, k)); }
  // Float storage only (std::logic_error on a compact grid).
  void set_voxel(int i, int j, int k, float density) {
    check_writable();
    density_[index(i, j, k)] = density;
  }
  void set_voxel(int i, int j, int k, float density, const Sggx& S) {
    check_writable();
    density_[index(i, j, k)] = density;
    sggx_[index(i, j, k)] = S;
  }
  // All voxels in index() order; sggx_data() is empty without S; both are empty for a compact grid.
  std::span<float> density_data() { return density_; }
  std::span<const float> density_data() const { return density_; }
  std::span<Sggx> sggx_data() { return sggx_; }
  std::span<const Sggx> sggx_data() const { return sggx_; }

  // Converts to compact storage (see the header comment); a no-op on a compact or empty grid.
  void compact();
  bool is_compact() const { return compact_; }

  const Vec3i& resolution() const { return res_; }
  size_t voxel_count() const { return count_; }
  const Vec3& lo() const { return lo_; }
  const Vec3& hi() const { return hi_; }
  Vec3 voxel_size() const { return (hi_ - lo_) / Vec3(res_); }
  bool has_sggx() const { return has_sggx_; }
  bool empty() const { return count_ == 0; }
  float max_density() const;
  // Bytes held by the voxel arrays (float: 4 per density, 24 per S; compact: 2 and 6).
  size_t memory_bytes() const {
    return density_.size() * sizeof(float) + sggx_.size() * sizeof(Sggx) + density16_.size() * sizeof(uint16_t) +
           sggx6_.size() * sizeof(SggxCompact);
  }

 private:
  struct Weights {
    size_t idx[8];
    float w[8];
  };
  // The eight voxels and trilinear weights for a point inside the box.
  Weights weights(const Vec3& p) const;
  bool inside(const Vec3& p) const {
    return p.x >= lo_.x && p.y >= lo_.y && p.z >= lo_.z && p.x <= hi_.x && p.y <= hi_.y && p.z <= hi_.z;
  }
  Sggx weighted_sggx(const Weights& w) const;
  void check_writable() const;
  static VoxelGrid parse_kvox_v2(const std::filesystem::path& file, std::string_view data);

  Vec3i res_{0};
  Vec3 lo_{0.0f}, hi_{0.0f};
  Vec3 voxels_per_unit_{0.0f};  // res / (hi - lo)
  size_t count_ = 0;
  bool has_sggx_ = false;
  bool compact_ = false;
  // Float storage.
  std::vector<float> density_;
  std::vector<Sggx> sggx_;  // empty, or one per voxel
  // Compact storage.
  std::vector<uint16_t> density16_;
  std::vector<SggxCompact> sggx6_;  // empty, or one per voxel
  float density_step_ = 0.0f;
  float sigma_scale_ = 1.0f;
};

// Level 0 is a copy of base, then each level halves the resolution (see the header comment) down to a single
// voxel. All levels share base's box; with a compact base the coarser levels are compacted too.
std::vector<VoxelGrid> build_mip_chain(const VoxelGrid& base);

}  // namespace kozu
