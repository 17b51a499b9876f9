// VoxelGrid: trilinear lookups, the MIP chain, and the .kvox / .vdb readers (formats in voxel_grid.h).
#include "media/voxel_grid.h"

#include "core/error.h"
#include "core/file_io.h"
#include "core/load_cache.h"
#include "core/memory.h"
#include "core/temp_files.h"

#include <fmt/format.h>
#include <oneapi/tbb/parallel_for.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <mutex>
#include <stdexcept>
#include <string>
#include <string_view>

namespace kozu {

namespace {

constexpr std::string_view kKvoxMagic = "KOZUVOX1";
constexpr std::string_view kKvox2Magic = "KOZUVOX2";
constexpr size_t kKvoxHeaderBytes = 48;
constexpr size_t kKvox2HeaderBytes = 56;
constexpr const char* kChannelNames[7] = {"density", "Sxx", "Syy", "Szz", "Sxy", "Sxz", "Syz"};

// Little-endian encoding by shifts, independent of the host's byte order.
uint32_t load_u32_le(const char* p) {
  const auto* b = reinterpret_cast<const unsigned char*>(p);
  return uint32_t{b[0]} | (uint32_t{b[1]} << 8) | (uint32_t{b[2]} << 16) | (uint32_t{b[3]} << 24);
}
float load_f32_le(const char* p) { return bits_as_float(load_u32_le(p)); }
void append_u32_le(std::string& out, uint32_t v) {
  const char bytes[4] = {static_cast<char>(v & 0xffu), static_cast<char>((v >> 8) & 0xffu),
                         static_cast<char>((v >> 16) & 0xffu), static_cast<char>((v >> 24) & 0xffu)};
  out.append(bytes, 4);
}
void append_f32_le(std::string& out, float v) { append_u32_le(out, float_as_bits(v)); }

// The header fields both versions share (after the magic): resolution, channels, box; checked.
struct KvoxHeader {
  uint32_t n[3];
  uint32_t channels;
  Vec3 lo, hi;
  uint64_t voxels;
};

std::array<float, 7> sggx_channels(float density, const Sggx& S) {
  return {density, S.xx, S.yy, S.zz, S.xy, S.xz, S.yz};
}

// Finite, density >= 0, S diagonals >= 0 and |r| <= 1 (eq. 19) within a relative 1e-3. Returns the
// problem, or an empty string.
std::string check_voxel(const float* v, int channels) {
  for (int c = 0; c < channels; ++c)
    if (!std::isfinite(v[c])) return fmt::format("{} is {}", kChannelNames[c], v[c]);
  if (v[0] < 0.0f) return fmt::format("negative density {}", v[0]);
  if (channels == 1) return {};
  for (int c = 1; c <= 3; ++c)
    if (v[c] < 0.0f) return fmt::format("negative {} {}", kChannelNames[c], v[c]);
  const auto off_diagonal_ok = [](float sab, float saa, float sbb) {
    return std::abs(sab) <= std::sqrt(saa * sbb) * 1.001f + 1e-30f;
  };
  if (!off_diagonal_ok(v[4], v[1], v[2])) return fmt::format("|Sxy| = {} exceeds sqrt(Sxx Syy)", std::abs(v[4]));
  if (!off_diagonal_ok(v[5], v[1], v[3])) return fmt::format("|Sxz| = {} exceeds sqrt(Sxx Szz)", std::abs(v[5]));
  if (!off_diagonal_ok(v[6], v[2], v[3])) return fmt::format("|Syz| = {} exceeds sqrt(Syy Szz)", std::abs(v[6]));
  return {};
}

// The grid, its MIP chain (at most 1/7 more) and majorants (1/8 of the voxels) must fit in the memory left.
void check_voxel_memory(const std::filesystem::path& file, const Vec3i& n, uint32_t channels, bool compact = false) {
  const double voxels = double(n.x) * double(n.y) * double(n.z);
  const double per_voxel = compact ? (channels == 7 ? 8.0 : 2.0) : (channels == 7 ? 4.0 + sizeof(Sggx) : 4.0);
  const double bytes = voxels * per_voxel * (8.0 / 7.0 + 1.0 / 8.0);
  const MemoryLimit limit = memory_limit();
  if (bytes > memory_left(limit))
    throw InputError(file.string(), "",
                     fmt::format("a {} x {} x {} grid needs about {}, more than is left of the {} limit ({})", n.x, n.y,
                                 n.z, format_bytes(bytes), format_bytes(double(limit.bytes)), limit.source));
}

}  // namespace

void check_voxel_grid_memory(const std::string& name, const Vec3i& n, bool sggx) {
  check_voxel_memory(name, n, sggx ? 7u : 1u, false);
}

namespace {

// Reads and checks the shared header fields and the file's size: `header_bytes` and, from `compact`, the bytes
// per voxel (version 2: 2 or 8; version 1: 4 per channel).
KvoxHeader parse_kvox_header(const std::filesystem::path& file, std::string_view data, size_t header_bytes,
                             bool compact) {
  const auto fail = [&](const std::string& message) -> void { throw InputError(file.string(), "", message); };
  if (data.size() < header_bytes)
    fail(fmt::format("truncated .kvox header: {} bytes, expected at least {}", data.size(), header_bytes));
  const char* p = data.data() + kKvoxMagic.size();
  KvoxHeader h{};
  for (int a = 0; a < 3; ++a) h.n[a] = load_u32_le(p + 4 * a);
  h.channels = load_u32_le(p + 12);
  for (int a = 0; a < 3; ++a) {
    h.lo[a] = load_f32_le(p + 16 + 4 * a);
    h.hi[a] = load_f32_le(p + 28 + 4 * a);
  }
  const uint32_t* n = h.n;
  if (n[0] == 0 || n[1] == 0 || n[2] == 0) fail(fmt::format("empty resolution {} x {} x {}", n[0], n[1], n[2]));
  h.voxels = 1;
  for (uint32_t na : h.n) {
    h.voxels *= na;
    if (h.voxels > VoxelGrid::kMaxVoxels)
      fail(fmt::format("resolution {} x {} x {} exceeds the limit of {} voxels", n[0], n[1], n[2],
                       VoxelGrid::kMaxVoxels));
  }
  if (h.channels != 1 && h.channels != 7)
    fail(fmt::format("unsupported channel count {} (expected 1 = density or 7 = density + SGGX S)", h.channels));
  check_voxel_memory(file, Vec3i(int(n[0]), int(n[1]), int(n[2])), h.channels, compact);
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(h.lo[a]) || !std::isfinite(h.hi[a]) || !(h.lo[a] < h.hi[a]))
      fail(fmt::format("invalid box lo = ({}, {}, {}), hi = ({}, {}, {})", h.lo.x, h.lo.y, h.lo.z, h.hi.x, h.hi.y,
                       h.hi.z));
  const uint64_t per_voxel = compact ? (h.channels == 7 ? 8 : 2) : uint64_t{h.channels} * 4;
  const uint64_t expected = h.voxels * per_voxel;
  const uint64_t found = data.size() - header_bytes;
  if (found < expected)
    fail(fmt::format("truncated voxel data: {} bytes, expected {} ({} x {} x {} voxels, {} channels)", found, expected,
                     n[0], n[1], n[2], h.channels));
  if (found > expected) fail(fmt::format("{} unexpected bytes after the voxel data", found - expected));
  return h;
}

VoxelGrid parse_kvox(const std::filesystem::path& file, std::string_view data) {
  const KvoxHeader h = parse_kvox_header(file, data, kKvoxHeaderBytes, false);
  const auto fail = [&](const std::string& message) -> void { throw InputError(file.string(), "", message); };
  const uint32_t* n = h.n;
  const uint32_t channels = h.channels;
  const Vec3 lo = h.lo, hi = h.hi;
  VoxelGrid grid(Vec3i{int(n[0]), int(n[1]), int(n[2])}, lo, hi, channels == 7);
  const char* values = data.data() + kKvoxHeaderBytes;
  const int nc = static_cast<int>(channels);
  for (int k = 0; k < int(n[2]); ++k)
    for (int j = 0; j < int(n[1]); ++j)
      for (int i = 0; i < int(n[0]); ++i) {
        const size_t idx = grid.index(i, j, k);
        float v[7] = {};
        for (int c = 0; c < nc; ++c) v[c] = load_f32_le(values + (idx * channels + size_t(c)) * 4);
        if (const std::string problem = check_voxel(v, nc); !problem.empty())
          fail(fmt::format("voxel ({}, {}, {}): {}", i, j, k, problem));
        if (nc == 7)
          grid.set_voxel(i, j, k, v[0], Sggx{v[1], v[2], v[3], v[4], v[5], v[6]});
        else
          grid.set_voxel(i, j, k, v[0]);
      }
  return grid;
}

// OpenVDB trusts the offsets and counts in a file: a truncated or forged file makes it allocate gigabytes or
// loop. Before OpenVDB sees the file, its header, metadata and grid descriptors are walked and every length
// and offset is checked against the file's size (the layout of openvdb::io::File, format versions 218-224:
// int64 magic "VDB ", uint32 version, uint32 library major and minor, a byte "has grid offsets", a 36-char
// UUID, the file metadata (int32 count; per entry a name and a type string and a uint32-sized value), an
// int32 grid count, then per grid a descriptor (name, type and, from version 216, instance-parent strings;
// int64 grid, block and end offsets) followed by the grid itself up to its end offset).
void check_vdb_structure(const std::filesystem::path& file) {
  const auto fail = [&](const std::string& message) -> void {
    throw InputError(file.string(), "", "not a valid OpenVDB file: " + message);
  };
  std::ifstream in = open_input_file(file);
  in.seekg(0, std::ios::end);
  const int64_t size = static_cast<int64_t>(in.tellg());
  in.seekg(0);
  int64_t pos = 0;
  const auto read = [&](void* out, int64_t n, const char* what) {
    if (n < 0 || pos + n > size)
      fail(fmt::format("{} at byte {} runs past the end of the file ({} bytes)", what, pos, size));
    in.seekg(pos);
    in.read(static_cast<char*>(out), n);
    if (!in) fail(fmt::format("cannot read {} at byte {}", what, pos));
    pos += n;
  };
  const auto u32 = [&](const char* what) {
    char b[4];
    read(b, 4, what);
    return load_u32_le(b);
  };
  const auto i64 = [&](const char* what) {
    char b[8];
    read(b, 8, what);
    return static_cast<int64_t>(uint64_t{load_u32_le(b)} | (uint64_t{load_u32_le(b + 4)} << 32));
  };
  // A string: uint32 length, then the bytes (only skipped here).
  const auto skip_string = [&](const char* what) {
    const uint32_t n = u32(what);
    if (pos + int64_t{n} > size)
      fail(fmt::format("{} of {} bytes at byte {} runs past the end of the file", what, n, pos));
    pos += n;
  };
  if (i64("the magic number") != 0x56444220) fail("bad magic number");
  const uint32_t version = u32("the format version");
  if (version < 218 || version > 224)
    fail(fmt::format("format version {} (kozu reads versions 218 to 224, OpenVDB 2 to 10)", version));
  u32("the library version");
  u32("the library version");
  char has_offsets = 0;
  read(&has_offsets, 1, "the grid-offsets flag");
  if (!has_offsets) fail("written as a stream without grid offsets (write it with openvdb::io::File)");
  char uuid[36];
  read(uuid, 36, "the UUID");
  const uint32_t entries = u32("the metadata count");
  for (uint32_t e = 0; e < entries; ++e) {
    skip_string("a metadata name");
    skip_string("a metadata type");
    skip_string("a metadata value");
  }
  const uint32_t grids = u32("the grid count");
  if (grids > static_cast<uint64_t>(size)) fail(fmt::format("{} grids in {} bytes", grids, size));
  for (uint32_t g = 0; g < grids; ++g) {
    skip_string("a grid name");
    skip_string("a grid type");
    if (version >= 216) skip_string("a grid's instance parent");
    const int64_t grid_pos = i64("a grid offset"), block_pos = i64("a block offset"), end_pos = i64("an end offset");
    if (!(pos <= grid_pos && grid_pos <= block_pos && block_pos <= end_pos && end_pos <= size))
      fail(fmt::format("grid {} claims bytes [{}, {}) of a {}-byte file (truncated?)", g, grid_pos, end_pos, size));
    pos = end_pos;
  }
}

VoxelGrid load_vdb(const std::filesystem::path& file) {
  const auto fail = [&](const std::string& message) -> void { throw InputError(file.string(), "", message); };
  check_vdb_structure(file);
  static std::once_flag init;
  std::call_once(init, [] { openvdb::initialize(); });

  openvdb::FloatGrid::Ptr grid;
  try {
    openvdb::io::File vdb(file.string());
    vdb.open(/*delayLoad=*/false);
    const openvdb::GridPtrVecPtr grids = vdb.getGrids();
    vdb.close();
    std::string found;
    for (const openvdb::GridBase::Ptr& g : *grids) {
      found += fmt::format("{}'{}' ({})", found.empty() ? "" : ", ", g->getName(), g->valueType());
      auto fg = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
      if (!fg) continue;
      if (!grid || (g->getName() == "density" && grid->getName() != "density")) grid = fg;
    }
    if (!grid) fail(fmt::format("no float grid in the file (grids: {})", found.empty() ? "none" : found));
  } catch (const openvdb::Exception& e) {
    fail(fmt::format("cannot read OpenVDB file: {}", e.what()));
  } catch (const std::bad_alloc&) {
    fail("cannot read OpenVDB file: it asks for more memory than there is (corrupt?)");
  }

  const std::string name = grid->getName();
  if (grid->getGridClass() == openvdb::GRID_LEVEL_SET)
    fail(fmt::format("grid '{}' is a level set, not a density grid", name));
  const openvdb::math::Transform& xf = grid->transform();
  if (!xf.isLinear()) fail(fmt::format("grid '{}' has a non-linear (frustum) transform", name));
  // The map must be world = index * voxel_size + translation with a positive per-axis scale.
  const openvdb::Vec3d origin = xf.indexToWorld(openvdb::Vec3d(0.0));
  for (int a = 0; a < 3; ++a) {
    openvdb::Vec3d e(0.0);
    e[a] = 1.0;
    const openvdb::Vec3d step = xf.indexToWorld(e) - origin;
    const double scale = step[a];
    const double off = std::max(std::abs(step[(a + 1) % 3]), std::abs(step[(a + 2) % 3]));
    if (!(scale > 0.0) || off > 1e-9 * scale)
      fail(
          fmt::format("grid '{}' has a rotated, sheared or mirrored transform; only a per-axis scale and a "
                      "translation are supported",
                      name));
  }

  const openvdb::CoordBBox bbox = grid->evalActiveVoxelBoundingBox();
  if (bbox.empty()) fail(fmt::format("grid '{}' has no active voxels", name));
  const openvdb::Coord dim = bbox.dim();
  const uint64_t voxels = uint64_t(dim.x()) * uint64_t(dim.y()) * uint64_t(dim.z());
  if (voxels > VoxelGrid::kMaxVoxels)
    fail(
        fmt::format("grid '{}': active bounding box {} x {} x {} exceeds the limit of {} voxels (kozu makes it "
                    "dense; crop or resample the grid)",
                    name, dim.x(), dim.y(), dim.z(), VoxelGrid::kMaxVoxels));
  check_voxel_memory(file, Vec3i(dim.x(), dim.y(), dim.z()), 1);
  const openvdb::Vec3d wlo = xf.indexToWorld(bbox.min().asVec3d() - openvdb::Vec3d(0.5));
  const openvdb::Vec3d whi = xf.indexToWorld(bbox.max().asVec3d() + openvdb::Vec3d(0.5));
  const Vec3 lo(float(wlo.x()), float(wlo.y()), float(wlo.z()));
  const Vec3 hi(float(whi.x()), float(whi.y()), float(whi.z()));
  if (!is_finite(lo) || !is_finite(hi) || !(lo.x < hi.x && lo.y < hi.y && lo.z < hi.z))
    fail(fmt::format("grid '{}' maps to an invalid box", name));

  VoxelGrid out(Vec3i(dim.x(), dim.y(), dim.z()), lo, hi, false);
  // LayoutXYZ (x fastest) is VoxelGrid's order, so OpenVDB writes straight into the grid.
  openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ> dense(bbox, out.density_data().data());
  openvdb::tools::copyToDense(*grid, dense);
  const std::span<const float> d = out.density_data();
  for (size_t idx = 0; idx < d.size(); ++idx) {
    if (std::isfinite(d[idx]) && d[idx] >= 0.0f) continue;
    const size_t i = idx % size_t(dim.x()), j = (idx / size_t(dim.x())) % size_t(dim.y()),
                 k = idx / (size_t(dim.x()) * size_t(dim.y()));
    fail(fmt::format("grid '{}': voxel ({}, {}, {}) has {} density {}", name, bbox.min().x() + int(i),
                     bbox.min().y() + int(j), bbox.min().z() + int(k), std::isfinite(d[idx]) ? "negative" : "invalid",
                     d[idx]));
  }
  return out;
}

}  // namespace

VoxelGrid::VoxelGrid(const Vec3i& resolution, const Vec3& lo, const Vec3& hi, bool has_sggx)
    : res_(resolution), lo_(lo), hi_(hi) {
  if (resolution.x < 1 || resolution.y < 1 || resolution.z < 1)
    throw std::invalid_argument(
        fmt::format("VoxelGrid: resolution {} x {} x {} is empty", resolution.x, resolution.y, resolution.z));
  if (!is_finite(lo) || !is_finite(hi) || !(lo.x < hi.x && lo.y < hi.y && lo.z < hi.z))
    throw std::invalid_argument("VoxelGrid: the box must be finite with lo < hi on every axis");
  voxels_per_unit_ = Vec3(res_) / (hi_ - lo_);
  count_ = size_t(res_.x) * size_t(res_.y) * size_t(res_.z);
  has_sggx_ = has_sggx;
  density_.assign(count_, 0.0f);
  if (has_sggx) sggx_.assign(count_, Sggx{});
}

void VoxelGrid::check_writable() const {
  if (compact_) throw std::logic_error("VoxelGrid: a compact grid is read-only");
}

VoxelGrid VoxelGrid::from_kvox_bytes(const std::filesystem::path& file, std::string_view data) {
  if (data.size() >= kKvox2Magic.size() && std::string_view(data.data(), kKvox2Magic.size()) == kKvox2Magic)
    return parse_kvox_v2(file, data);
  if (data.size() >= kKvoxMagic.size() && std::string_view(data.data(), kKvoxMagic.size()) != kKvoxMagic)
    throw InputError(file.string(), "",
                     fmt::format("not a .kvox file: bad magic (expected \"{}\" or \"{}\")", kKvoxMagic, kKvox2Magic));
  return parse_kvox(file, data);
}

VoxelGrid VoxelGrid::parse_kvox_v2(const std::filesystem::path& file, std::string_view data) {
  const KvoxHeader h = parse_kvox_header(file, data, kKvox2HeaderBytes, true);
  const auto fail = [&](const std::string& message) -> void { throw InputError(file.string(), "", message); };
  const float step = load_f32_le(data.data() + 48), scale = load_f32_le(data.data() + 52);
  if (!std::isfinite(step) || step < 0.0f) fail(fmt::format("invalid density step {}", step));
  if (!std::isfinite(scale) || !(scale > 0.0f)) fail(fmt::format("invalid sigma scale {}", scale));
  VoxelGrid grid;
  grid.res_ = Vec3i(int(h.n[0]), int(h.n[1]), int(h.n[2]));
  grid.lo_ = h.lo;
  grid.hi_ = h.hi;
  grid.voxels_per_unit_ = Vec3(grid.res_) / (grid.hi_ - grid.lo_);
  grid.count_ = h.voxels;
  grid.has_sggx_ = h.channels == 7;
  grid.compact_ = true;
  grid.density_step_ = step;
  grid.sigma_scale_ = scale;
  grid.density16_.resize(grid.count_);
  if (grid.has_sggx_) grid.sggx6_.resize(grid.count_);
  const size_t per_voxel = grid.has_sggx_ ? 8 : 2;
  const auto* bytes = reinterpret_cast<const unsigned char*>(data.data() + kKvox2HeaderBytes);
  for (size_t idx = 0; idx < grid.count_; ++idx) {
    const unsigned char* v = bytes + idx * per_voxel;
    grid.density16_[idx] = static_cast<uint16_t>(v[0] | (v[1] << 8));
    if (!grid.has_sggx_) continue;
    SggxCompact& c = grid.sggx6_[idx];
    for (size_t a = 0; a < 3; ++a) {
      c.sigma[a] = v[2 + a];
      c.r[a] = static_cast<int8_t>(v[5 + a]);
    }
    if (!sggx::correlations_pass_guard(c)) {
      const int i = int(idx % size_t(grid.res_.x)), j = int(idx / size_t(grid.res_.x) % size_t(grid.res_.y)),
                k = int(idx / (size_t(grid.res_.x) * size_t(grid.res_.y)));
      fail(fmt::format("voxel ({}, {}, {}): its correlations ({}, {}, {}) / 127 are not positive definite", i, j, k,
                       c.r[0], c.r[1], c.r[2]));
    }
  }
  return grid;
}

void VoxelGrid::compact() {
  if (compact_ || empty()) return;
  density_step_ = max_density() / 65535.0f;
  float scale = 0.0f;
  for (const Sggx& S : sggx_) scale = std::max({scale, S.xx, S.yy, S.zz});
  sigma_scale_ = scale > 0.0f ? std::sqrt(scale) : 1.0f;
  density16_.resize(count_);
  if (has_sggx_) sggx6_.resize(count_);
  const float inv_step = density_step_ > 0.0f ? 1.0f / density_step_ : 0.0f;
  tbb::parallel_for(size_t{0}, count_, [&](size_t idx) {
    density16_[idx] = static_cast<uint16_t>(std::min(65535.0f, std::round(density_[idx] * inv_step)));
    if (has_sggx_) sggx6_[idx] = sggx::compress_spd(sggx_[idx], sigma_scale_);
  });
  std::vector<float>().swap(density_);
  std::vector<Sggx>().swap(sggx_);
  compact_ = true;
}

VoxelGrid VoxelGrid::load(const std::filesystem::path& file) {
  const std::string ext = lower_extension(file);
  // The showcase volumes are generated, not checked in: say how to make a missing one.
  std::error_code ec;
  if (!std::filesystem::exists(file, ec) && file.parent_path().filename() == "volumes" && ext == ".kvox") {
    const std::string stem = file.stem().string();
    if (stem == "bush")
      throw InputError(file.string(), "",
                       "no such file: kozu's voxelized bush is generated, not checked in; run "
                       "scripts/make-volumes.sh once (from the repository root, after building) to write it");
    if (stem == "smoke" || stem == "yarn" || stem == "fabric")
      throw InputError(file.string(), "",
                       fmt::format("no such file: kozu's showcase scenes generate this volume at load; write "
                                   "\"procedural\": \"{}\" instead of the \"file\" (or make the file with "
                                   "`kozu procedural {} -o {}`)",
                                   stem, stem, file.string()));
  }
  if (ext == ".kvox")
    return cached_load<VoxelGrid>("voxels", file, "", [&] { return from_kvox_bytes(file, read_input_file(file)); });
  if (ext == ".vdb") return cached_load<VoxelGrid>("voxels", file, "", [&] { return load_vdb(file); });
  throw InputError(file.string(), "", fmt::format("unknown voxel grid format '{}' (expected .vdb or .kvox)", ext));
}

void VoxelGrid::save_kvox(const std::filesystem::path& file) const {
  if (empty()) throw std::runtime_error(fmt::format("{}: cannot save an empty voxel grid", file.string()));
  const uint32_t channels = has_sggx() ? 7 : 1;
  std::string out;
  out.reserve(kKvox2HeaderBytes + voxel_count() * channels * 4);
  out.append(compact_ ? kKvox2Magic : kKvoxMagic);
  for (int a = 0; a < 3; ++a) append_u32_le(out, uint32_t(res_[a]));
  append_u32_le(out, channels);
  for (int a = 0; a < 3; ++a) append_f32_le(out, lo_[a]);
  for (int a = 0; a < 3; ++a) append_f32_le(out, hi_[a]);
  if (compact_) {
    append_f32_le(out, density_step_);
    append_f32_le(out, sigma_scale_);
    for (size_t idx = 0; idx < voxel_count(); ++idx) {
      out.push_back(static_cast<char>(density16_[idx] & 0xffu));
      out.push_back(static_cast<char>(density16_[idx] >> 8));
      if (!has_sggx_) continue;
      for (uint8_t v : sggx6_[idx].sigma) out.push_back(static_cast<char>(v));
      for (int8_t v : sggx6_[idx].r) out.push_back(static_cast<char>(v));
    }
    write_file_atomic(file, out);
    return;
  }
  for (size_t idx = 0; idx < voxel_count(); ++idx) {
    if (channels == 1) {
      append_f32_le(out, density_[idx]);
    } else {
      for (float v : sggx_channels(density_[idx], sggx_[idx])) append_f32_le(out, v);
    }
  }
  write_file_atomic(file, out);
}

void VoxelGrid::save_vdb(const std::filesystem::path& file) const {
  if (empty()) throw std::runtime_error(fmt::format("{}: cannot save an empty voxel grid", file.string()));
  if (has_sggx())
    throw std::runtime_error(fmt::format("{}: an OpenVDB file cannot hold the grid's SGGX matrices (use .kvox)",
                                         file.string()));
  static std::once_flag init;
  std::call_once(init, [] { openvdb::initialize(); });
  openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(0.0f);
  grid->setName("density");
  grid->setGridClass(openvdb::GRID_FOG_VOLUME);
  // index (i, j, k) is the centre of voxel (i, j, k): world = lo + (index + 1/2) · size per axis.
  const Vec3 size = voxel_size();
  openvdb::math::MapBase::Ptr map(new openvdb::math::ScaleTranslateMap(
      openvdb::Vec3d(size.x, size.y, size.z),
      openvdb::Vec3d(lo_.x + 0.5 * size.x, lo_.y + 0.5 * size.y, lo_.z + 0.5 * size.z)));
  grid->setTransform(openvdb::math::Transform::Ptr(new openvdb::math::Transform(map)));
  const openvdb::CoordBBox box(openvdb::Coord(0), openvdb::Coord(res_.x - 1, res_.y - 1, res_.z - 1));
  std::vector<float> decoded;
  if (compact_) {
    decoded.resize(count_);
    for (size_t idx = 0; idx < count_; ++idx) decoded[idx] = density_at(idx);
  }
  openvdb::tools::Dense<const float, openvdb::tools::LayoutXYZ> dense(box, compact_ ? decoded.data() : density_.data());
  openvdb::tools::copyFromDense(dense, *grid, /*tolerance=*/0.0f);
  TempFileGuard tmp(temp_path_for(file));
  try {
    openvdb::io::File out(tmp.path().string());
    // The file is created as the write starts; the window lasts the whole write (a stop waits at most 0.5 s).
    create_temp_file([&] { out.write(openvdb::GridPtrVec{grid}); });
    out.close();
  } catch (const openvdb::Exception& e) {
    throw std::runtime_error(fmt::format("{}: cannot write OpenVDB file: {}", file.string(), e.what()));
  }
  rename_into_place(tmp, file);
}

VoxelGrid::Weights VoxelGrid::weights(const Vec3& p) const {
  // Per axis: the two neighbouring voxel centres (clamped to the edge) as index offsets, and their weights;
  // corner c takes bit 0 for x, bit 1 for y, bit 2 for z. Offsets are added, not recomputed per corner, as
  // this runs at every tentative collision of delta and ratio tracking.
  const size_t stride[3] = {1, static_cast<size_t>(res_.x), static_cast<size_t>(res_.x) * static_cast<size_t>(res_.y)};
  size_t off[3][2];
  float wt[3][2];
  for (int a = 0; a < 3; ++a) {
    // Continuous voxel coordinate with voxel centres at integers; clamp-to-edge on both neighbours.
    const float u = (p[a] - lo_[a]) * voxels_per_unit_[a] - 0.5f;
    const float fl = std::floor(u);
    const float f = u - fl;
    const int base = static_cast<int>(fl);
    off[a][0] = static_cast<size_t>(std::clamp(base, 0, res_[a] - 1)) * stride[a];
    off[a][1] = static_cast<size_t>(std::clamp(base + 1, 0, res_[a] - 1)) * stride[a];
    wt[a][0] = 1.0f - f;
    wt[a][1] = f;
  }
  Weights out;
  for (int c = 0; c < 8; ++c) {
    const int x = c & 1, y = (c >> 1) & 1, z = c >> 2;
    out.idx[c] = off[0][x] + off[1][y] + off[2][z];
    out.w[c] = wt[0][x] * wt[1][y] * wt[2][z];
  }
  return out;
}

Sggx VoxelGrid::weighted_sggx(const Weights& w) const {
  // Density-weighted convex combination of the six coefficients (header comment); plain weights if empty.
  float wr[8], sum = 0.0f;
  for (int c = 0; c < 8; ++c) {
    wr[c] = w.w[c] * density_at(w.idx[c]);
    sum += wr[c];
  }
  const bool weighted = sum > 0.0f;
  const float inv = weighted ? 1.0f / sum : 1.0f;
  Sggx S{0, 0, 0, 0, 0, 0};
  for (int c = 0; c < 8; ++c) S = S + sggx_at(w.idx[c]) * ((weighted ? wr[c] : w.w[c]) * inv);
  return S;
}

float VoxelGrid::density(const Vec3& p) const {
  if (empty() || !inside(p)) return 0.0f;
  const Weights w = weights(p);
  float d = 0.0f;
  if (compact_) {
    for (int c = 0; c < 8; ++c) d += w.w[c] * float(density16_[w.idx[c]]);
    return d * density_step_;
  }
  for (int c = 0; c < 8; ++c) d += w.w[c] * density_[w.idx[c]];
  return d;
}

Sggx VoxelGrid::sggx(const Vec3& p) const {
  if (!has_sggx()) return Sggx{};
  // Outside the box: the clamped edge value (the point is moved onto the box; density is 0 there anyway).
  const Vec3 q = glm::clamp(p, lo_, hi_);
  if (!is_finite(q)) return Sggx{};
  return weighted_sggx(weights(q));
}

VoxelGrid::Lookup VoxelGrid::lookup(const Vec3& p) const {
  Lookup out;
  if (empty() || !inside(p)) {
    out.sggx = sggx(p);
    return out;
  }
  const Weights w = weights(p);
  for (int c = 0; c < 8; ++c) out.density += w.w[c] * density_at(w.idx[c]);
  if (has_sggx()) out.sggx = weighted_sggx(w);
  return out;
}

float VoxelGrid::sggx_extinction(const Vec3& p, const Vec3& w) const {
  if (!inside(p)) return 0.0f;
  const Weights wt = weights(p);
  // ωᵀ S ω = Sxx x² + Syy y² + Szz z² + 2 (Sxy xy + Sxz xz + Syz yz), the products once per lookup.
  const float xx = w.x * w.x, yy = w.y * w.y, zz = w.z * w.z;
  const float xy = 2.0f * w.x * w.y, xz = 2.0f * w.x * w.z, yz = 2.0f * w.y * w.z;
  float rho = 0.0f, q = 0.0f;
  if (compact_) {
    // From the codes (eq. 20): with v = σ ∘ ω, ωᵀSω = v·v + 2 (rxy vx vy + rxz vx vz + ryz vy vz).
    const Vec3 wk = w * (sigma_scale_ / 255.0f);
    constexpr float kr = 2.0f / 127.0f;
    for (int c = 0; c < 8; ++c) {
      const uint16_t code = density16_[wt.idx[c]];
      if (code == 0) continue;
      const float r = wt.w[c] * float(code);
      const SggxCompact& S = sggx6_[wt.idx[c]];
      const float vx = wk.x * S.sigma[0], vy = wk.y * S.sigma[1], vz = wk.z * S.sigma[2];
      rho += r;
      q += r * (vx * vx + vy * vy + vz * vz + kr * (S.r[0] * vx * vy + S.r[1] * vx * vz + S.r[2] * vy * vz));
    }
    return density_step_ * std::sqrt(std::max(0.0f, rho * q));
  }
  for (int c = 0; c < 8; ++c) {
    const float r = wt.w[c] * density_[wt.idx[c]];
    if (r == 0.0f) continue;
    const Sggx& S = sggx_[wt.idx[c]];
    rho += r;
    q += r * (S.xx * xx + S.yy * yy + S.zz * zz + S.xy * xy + S.xz * xz + S.yz * yz);
  }
  return std::sqrt(std::max(0.0f, rho * q));
}

float VoxelGrid::max_density() const {
  if (compact_) {
    uint16_t m = 0;
    for (uint16_t d : density16_) m = std::max(m, d);
    return float(m) * density_step_;
  }
  float m = 0.0f;
  for (float d : density_) m = std::max(m, d);
  return m;
}

std::vector<VoxelGrid> build_mip_chain(const VoxelGrid& base) {
  std::vector<VoxelGrid> chain;
  if (base.empty()) return chain;
  chain.push_back(base);
  while (chain.back().resolution() != Vec3i(1)) {
    const VoxelGrid& fine = chain.back();
    const Vec3i fr = fine.resolution();
    const Vec3i cr = glm::max(Vec3i(1), (fr + 1) / 2);
    VoxelGrid coarse(cr, fine.lo(), fine.hi(), fine.has_sggx());
    tbb::parallel_for(0, cr.z, [&](int k) {
      for (int j = 0; j < cr.y; ++j)
        for (int i = 0; i < cr.x; ++i) {
          // The 2x2x2 block, clamped on odd axes (the edge voxel counts twice).
          float dsum = 0.0f;
          Sggx weighted{0, 0, 0, 0, 0, 0}, plain{0, 0, 0, 0, 0, 0};
          for (int c = 0; c < 8; ++c) {
            const int fi = std::min(2 * i + (c & 1), fr.x - 1), fj = std::min(2 * j + ((c >> 1) & 1), fr.y - 1),
                      fk = std::min(2 * k + ((c >> 2) & 1), fr.z - 1);
            const float d = fine.voxel_density(fi, fj, fk);
            dsum += d;
            if (fine.has_sggx()) {
              const Sggx S = fine.voxel_sggx(fi, fj, fk);
              weighted = weighted + S * d;
              plain = plain + S;
            }
          }
          if (coarse.has_sggx())
            coarse.set_voxel(i, j, k, dsum * 0.125f, dsum > 0.0f ? weighted * (1.0f / dsum) : plain * 0.125f);
          else
            coarse.set_voxel(i, j, k, dsum * 0.125f);
        }
    });
    if (base.is_compact()) coarse.compact();
    chain.push_back(std::move(coarse));
  }
  return chain;
}

}  // namespace kozu
