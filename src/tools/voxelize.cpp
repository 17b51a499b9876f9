// voxelize_mesh: exact triangle/voxel clipping, then per-voxel area density and SGGX estimate (voxelize.h).
#include "tools/voxelize.h"

#include <fmt/format.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

namespace kozu {

namespace {

// A convex polygon in voxel coordinates. A triangle cut by three pairs of slab planes has at most 9 vertices;
// the spare room absorbs rounding on near-degenerate input.
struct Polygon {
  static constexpr int kCapacity = 16;
  std::array<Vec3d, kCapacity> v;
  int n = 0;
  void push(const Vec3d& p) {
    if (n < kCapacity) v[static_cast<size_t>(n++)] = p;
  }
};

// Sutherland–Hodgman against the plane p[axis] = c: `below` gets the part with p[axis] <= c, `above` the part with
// p[axis] >= c. A polygon lying in the plane goes to `below` only, so no area is counted twice.
void split(const Polygon& in, int axis, double c, Polygon& below, Polygon& above) {
  below.n = above.n = 0;
  bool in_plane = true;
  for (int i = 0; i < in.n; ++i) in_plane = in_plane && in.v[size_t(i)][axis] == c;
  if (in_plane) {
    below = in;
    return;
  }
  for (int i = 0; i < in.n; ++i) {
    const Vec3d& a = in.v[size_t(i)];
    const Vec3d& b = in.v[size_t((i + 1) % in.n)];
    const double da = a[axis] - c, db = b[axis] - c;
    if (da <= 0.0) below.push(a);
    if (da >= 0.0) above.push(a);
    if ((da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0)) {
      Vec3d p = a + (b - a) * (da / (da - db));
      p[axis] = c;
      below.push(p);
      above.push(p);
    }
  }
}

// Cuts `poly` into the slabs [i, i + 1) of `axis` (cells clamped to [0, n - 1]) and calls f(i, piece).
template <class F>
void for_each_slab(const Polygon& poly, int axis, int n, F&& f) {
  double lo = poly.v[0][axis], hi = lo;
  for (int i = 1; i < poly.n; ++i) {
    lo = std::min(lo, poly.v[size_t(i)][axis]);
    hi = std::max(hi, poly.v[size_t(i)][axis]);
  }
  const int first = std::clamp(static_cast<int>(std::floor(lo)), 0, n - 1);
  const int last = std::clamp(static_cast<int>(std::floor(hi)), 0, n - 1);
  Polygon rest = poly, below, above;
  for (int c = first; c < last; ++c) {
    split(rest, axis, double(c + 1), below, above);
    if (below.n >= 3) f(c, below);
    rest = above;
    if (rest.n < 3) return;
  }
  f(last, rest);
}

double polygon_area(const Polygon& p) {
  Vec3d sum(0.0);
  for (int i = 1; i + 1 < p.n; ++i) sum += glm::cross(p.v[size_t(i)] - p.v[0], p.v[size_t(i + 1)] - p.v[0]);
  return 0.5 * glm::length(sum);
}

struct Piece {
  uint64_t voxel;
  uint32_t triangle;
  float area;  // world units
  bool operator<(const Piece& o) const { return voxel != o.voxel ? voxel < o.voxel : triangle < o.triangle; }
};

}  // namespace

VoxelGrid voxelize_mesh(const MeshData& mesh, int resolution, VoxelizeStats* stats) {
  if (resolution < 4 || resolution > 1024)
    throw std::invalid_argument(fmt::format("resolution {} is outside [4, 1024]", resolution));
  const size_t triangle_count = mesh.indices.size() / 3;
  if (triangle_count == 0) throw std::invalid_argument("the mesh has no triangles");
  if (triangle_count > UINT32_MAX) throw std::invalid_argument("the mesh has more than 2^32 triangles");

  // Bounds of the vertices that triangles use.
  Vec3d bmin(kInfinity), bmax(-kInfinity);
  for (uint32_t idx : mesh.indices) {
    if (idx >= mesh.positions.size()) throw std::invalid_argument(fmt::format("vertex index {} out of range", idx));
    const Vec3d p(mesh.positions[idx]);
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw std::invalid_argument("the mesh has a non-finite vertex");
    bmin = glm::min(bmin, p);
    bmax = glm::max(bmax, p);
  }
  const Vec3d extent = bmax - bmin;
  int longest = 0;
  for (int a = 1; a < 3; ++a)
    if (extent[a] > extent[longest]) longest = a;
  if (!(extent[longest] > 0.0)) throw std::invalid_argument("the mesh has zero extent");

  // Cubic voxels, N along the longest axis, centred, with a border of more than one voxel (voxelize.h).
  const double h = extent[longest] / double(resolution - 3);
  Vec3i res;
  Vec3d lo;
  for (int a = 0; a < 3; ++a) {
    res[a] = a == longest ? resolution : std::min(resolution, static_cast<int>(std::floor(extent[a] / h)) + 3);
    lo[a] = 0.5 * (bmin[a] + bmax[a]) - 0.5 * h * res[a];
  }
  const Vec3d hi = lo + h * Vec3d(res);
  VoxelGrid grid(res, Vec3(lo), Vec3(hi), /*has_sggx=*/true);
  // Rounding to float may move the box by an ulp; voxel coordinates below use the float box, as lookups do.
  const Vec3d flo(grid.lo()), fscale = Vec3d(res) / (Vec3d(grid.hi()) - flo);

  // Clip triangles in fixed chunks (deterministic regardless of the thread count).
  constexpr size_t kChunk = 256;
  const size_t chunks = (triangle_count + kChunk - 1) / kChunk;
  std::vector<std::vector<Piece>> chunk_pieces(chunks);
  std::vector<Vec3> normals(triangle_count, Vec3(0.0f));
  std::vector<double> tri_area(triangle_count, 0.0);
  tbb::parallel_for(size_t{0}, chunks, [&](size_t chunk) {
    std::vector<Piece>& out = chunk_pieces[chunk];
    const size_t end = std::min(triangle_count, (chunk + 1) * kChunk);
    for (size_t t = chunk * kChunk; t < end; ++t) {
      const Vec3d p0(mesh.positions[mesh.indices[3 * t]]), p1(mesh.positions[mesh.indices[3 * t + 1]]),
          p2(mesh.positions[mesh.indices[3 * t + 2]]);
      const Vec3d c = glm::cross(p1 - p0, p2 - p0);
      const double len = glm::length(c);
      if (!(len > 0.0)) continue;  // degenerate
      normals[t] = Vec3(c / len);
      tri_area[t] = 0.5 * len;
      Polygon tri;
      for (const Vec3d& p : {p0, p1, p2}) tri.push((p - flo) * fscale);
      const double voxel_area = h * h;  // a unit of area in voxel coordinates
      for_each_slab(tri, 0, res.x, [&](int i, const Polygon& px) {
        for_each_slab(px, 1, res.y, [&](int j, const Polygon& py) {
          for_each_slab(py, 2, res.z, [&](int k, const Polygon& pz) {
            const double area = polygon_area(pz) * voxel_area;
            if (area > 0.0) out.push_back({grid.index(i, j, k), static_cast<uint32_t>(t), static_cast<float>(area)});
          });
        });
      });
    }
  });
  std::vector<Piece> pieces;
  {
    size_t total = 0;
    for (const auto& c : chunk_pieces) total += c.size();
    pieces.reserve(total);
    for (auto& c : chunk_pieces) {
      pieces.insert(pieces.end(), c.begin(), c.end());
      std::vector<Piece>().swap(c);
    }
  }
  // Keys (voxel, triangle) are unique, so the sorted order does not depend on the sort's scheduling.
  tbb::parallel_sort(pieces.begin(), pieces.end());

  // Runs of equal voxel; each reduced in triangle order.
  std::vector<size_t> starts;
  for (size_t i = 0; i < pieces.size(); ++i)
    if (i == 0 || pieces[i].voxel != pieces[i - 1].voxel) starts.push_back(i);
  starts.push_back(pieces.size());
  const size_t occupied = starts.size() - 1;
  const double inv_volume = 1.0 / (h * h * h);
  const std::span<float> density = grid.density_data();
  const std::span<Sggx> sggx = grid.sggx_data();
  tbb::parallel_for(size_t{0}, occupied, [&](size_t r) {
    std::vector<WeightedNormal> normal_set;
    normal_set.reserve(starts[r + 1] - starts[r]);
    double area = 0.0;
    for (size_t i = starts[r]; i < starts[r + 1]; ++i) {
      area += pieces[i].area;
      normal_set.push_back({normals[pieces[i].triangle], pieces[i].area});
    }
    const uint64_t voxel = pieces[starts[r]].voxel;
    density[voxel] = static_cast<float>(area * inv_volume);
    sggx[voxel] = sggx::estimate_from_normals(normal_set);
  });

  if (stats) {
    *stats = VoxelizeStats{};
    for (size_t t = 0; t < triangle_count; ++t) {
      stats->triangles += tri_area[t] > 0.0 ? 1 : 0;
      stats->mesh_area += tri_area[t];
    }
    stats->pieces = pieces.size();
    stats->occupied_voxels = occupied;
    const double voxel_volume = double(grid.voxel_size().x) * grid.voxel_size().y * grid.voxel_size().z;
    for (float d : grid.density_data()) stats->deposited_area += double(d) * voxel_volume;
  }
  if (occupied == 0) throw std::invalid_argument("the mesh has no triangle of positive area");
  return grid;
}

}  // namespace kozu
