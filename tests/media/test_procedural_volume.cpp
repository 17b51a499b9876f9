// Tests for the procedural volumes (media/procedural_volume.h) and `kozu procedural`: valid voxels, fiber-like
// SGGX matrices about tangents that follow the yarn / threads and are tilted by the ply twist, the yarn's shell,
// the weave's warp/weft structure, determinism, the .kvox round trip, resolution checks and the command line.
#include "media/procedural_volume.h"

#include "media/sggx.h"
#include "media/voxel_grid.h"
#include "support/render_test.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace kozu {
namespace {

namespace fs = std::filesystem;
using namespace procedural;

Vec3 voxel_centre(const VoxelGrid& g, int i, int j, int k) {
  return g.lo() + (Vec3(float(i), float(j), float(k)) + 0.5f) * g.voxel_size();
}

// Calls f(i, j, k, centre, density, S) for every voxel with density > 0; returns their number.
size_t for_each_occupied(const VoxelGrid& g,
                         const std::function<void(int, int, int, const Vec3&, float, const Sggx&)>& f) {
  size_t count = 0;
  const Vec3i r = g.resolution();
  for (int k = 0; k < r.z; ++k)
    for (int j = 0; j < r.y; ++j)
      for (int i = 0; i < r.x; ++i) {
        const float d = g.voxel_density(i, j, k);
        if (d <= 0.0f) continue;
        ++count;
        f(i, j, k, voxel_centre(g, i, j, k), d, g.has_sggx() ? g.voxel_sggx(i, j, k) : Sggx{});
      }
  return count;
}

// Every value finite, densities in [0, max_density], empty voxels with the default S, occupied ones SPD.
void expect_valid(const VoxelGrid& g, float max_density) {
  size_t bad_density = 0, bad_empty = 0, bad_spd = 0;
  const auto dens = g.density_data();
  for (size_t v = 0; v < dens.size(); ++v) {
    const float d = dens[v];
    if (!std::isfinite(d) || d < 0.0f || d > max_density) ++bad_density;
    if (!g.has_sggx()) continue;
    const Sggx& S = g.sggx_data()[v];
    if (d == 0.0f) {
      const Sggx I{};
      if (S.xx != I.xx || S.yy != I.yy || S.zz != I.zz || S.xy != I.xy || S.xz != I.xz || S.yz != I.yz) ++bad_empty;
    } else if (!sggx::is_spd(S)) {
      ++bad_spd;
    }
  }
  EXPECT_EQ(bad_density, 0u);
  EXPECT_EQ(bad_empty, 0u);
  EXPECT_EQ(bad_spd, 0u);
}

// Fiber-like S (eqs. 15–16): eigenvalues (1, 1, σ²); returns the tangent (the smallest eigenvalue's
// eigenvector), after checking S t = σ² t.
Vec3 fiber_tangent(const Sggx& S, size_t* failures) {
  const sggx::SymmetricEigen e = sggx::eigen(S);
  const double s2 = double(kFiberRoughness) * kFiberRoughness;
  const Vec3 t = Vec3(e.vectors[2]);
  const Vec3 St(S.xx * t.x + S.xy * t.y + S.xz * t.z, S.xy * t.x + S.yy * t.y + S.yz * t.z,
                S.xz * t.x + S.yz * t.y + S.zz * t.z);
  const bool ok = std::abs(e.values[0] - 1.0) < 1e-4 && std::abs(e.values[1] - 1.0) < 1e-4 &&
                  std::abs(e.values[2] / e.values[0] - s2) < 1e-3 * s2 && glm::length(St - float(s2) * t) < 1e-4f;
  if (!ok) ++*failures;
  return t;
}

// Voxel for voxel, bit for bit, through the accessors (so float and compact grids compare alike).
bool same_bytes(const VoxelGrid& a, const VoxelGrid& b) {
  if (a.resolution() != b.resolution() || a.lo() != b.lo() || a.hi() != b.hi() || a.has_sggx() != b.has_sggx() ||
      a.voxel_count() != b.voxel_count())
    return false;
  for (size_t idx = 0; idx < a.voxel_count(); ++idx) {
    const float da = a.density_at(idx), db = b.density_at(idx);
    if (std::memcmp(&da, &db, sizeof(float)) != 0) return false;
    if (!a.has_sggx()) continue;
    const Sggx sa = a.sggx_at(idx), sb = b.sggx_at(idx);
    if (std::memcmp(&sa, &sb, sizeof(Sggx)) != 0) return false;
  }
  return true;
}

TEST(ProceduralVolume, SmokePlume) {
  const VoxelGrid g = make_smoke_plume(32);
  EXPECT_EQ(g.resolution(), Vec3i(32));
  EXPECT_EQ(g.lo(), Vec3(-1.0f, 0.0f, -1.0f));
  EXPECT_EQ(g.hi(), Vec3(1.0f, 2.0f, 1.0f));
  EXPECT_FALSE(g.has_sggx());
  expect_valid(g, 2.5f);
  // A plume: occupied, around the axis (the widest radius is 0.7 plus the swirl's 0.15 ⋅ √2), not everywhere.
  size_t outside = 0;
  const size_t occupied = for_each_occupied(g, [&](int, int, int, const Vec3& p, float, const Sggx&) {
    outside += std::hypot(p.x, p.z) > 0.7f + 0.22f ? 1 : 0;
  });
  EXPECT_GT(occupied, g.voxel_count() / 50);
  EXPECT_LT(occupied, g.voxel_count() / 2);
  EXPECT_EQ(outside, 0u);
}

TEST(ProceduralVolume, YarnBallFibersFollowTwistedStrands) {
  const int n = 96;
  const VoxelGrid g = make_yarn_ball(n);
  EXPECT_EQ(g.resolution(), Vec3i(n));
  EXPECT_EQ(g.lo(), Vec3(-1.0f));
  EXPECT_EQ(g.hi(), Vec3(1.0f));
  ASSERT_TRUE(g.has_sggx());
  expect_valid(g, kYarnDensity);
  const float voxel = g.voxel_size().x;
  size_t outside_shell = 0, not_fiber = 0;
  double sum_radial = 0.0;
  float max_radial = 0.0f;
  const size_t occupied = for_each_occupied(g, [&](int, int, int, const Vec3& p, float, const Sggx& S) {
    const float r = glm::length(p);
    if (std::abs(r - kYarnBallRadius) > kYarnStrandRadius + voxel) ++outside_shell;
    // Strands follow great circles, whose tangents are ⟂ the radius; only the twist tilts the fibers out of
    // the sphere: the helix tangent's radial part is m r_p b sin θ against R − r_p b along the circle (m = 40
    // twists per circle, r_p = 0.45, b = 0.7 strand radii), at most atan(0.33 / 0.78) ≈ 23°, sin ≈ 0.39.
    const Vec3 t = fiber_tangent(S, &not_fiber);
    const float radial = std::abs(glm::dot(t, p / r));
    sum_radial += radial;
    max_radial = std::max(max_radial, radial);
  });
  EXPECT_EQ(outside_shell, 0u);
  EXPECT_EQ(not_fiber, 0u);
  // Most of the shell is covered (about ten strands cross every point of the sphere).
  size_t shell = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        shell += std::abs(glm::length(voxel_centre(g, i, j, k)) - kYarnBallRadius) < 0.5f * kYarnStrandRadius;
  EXPECT_GT(occupied, shell * 3 / 4) << shell;
  EXPECT_LT(max_radial, 0.42f);
  const double mean_radial = sum_radial / double(occupied);
  EXPECT_GT(mean_radial, 0.15) << "the twist should tilt the fibers against the strand";
}

// The ball's settings (YarnSettings) shape it: wider strands reach further from the sphere than the default's, and
// without a twist every fiber runs along its great circle, tangent to the sphere (the default's twist tilts them by
// up to 23 degrees, above). Fewer strands cover less of the shell.
TEST(ProceduralVolume, YarnSettingsShapeTheBall) {
  const int n = 96;
  YarnSettings y;
  y.strands = 40;
  y.strand_radius = 0.06f;
  y.twists_per_unit = 0.0f;
  const VoxelGrid g = make_yarn_ball(n, y);
  expect_valid(g, kYarnDensity);
  const float voxel = g.voxel_size().x;
  size_t outside_shell = 0, beyond_default = 0, not_fiber = 0;
  float max_radial = 0.0f;
  const size_t occupied = for_each_occupied(g, [&](int, int, int, const Vec3& p, float, const Sggx& S) {
    const float r = glm::length(p);
    outside_shell += std::abs(r - kYarnBallRadius) > y.strand_radius + voxel;
    beyond_default += std::abs(r - kYarnBallRadius) > kYarnStrandRadius + voxel;
    max_radial = std::max(max_radial, std::abs(glm::dot(fiber_tangent(S, &not_fiber), p / r)));
  });
  EXPECT_EQ(outside_shell, 0u);
  EXPECT_GT(beyond_default, occupied / 100);  // the default ball has none (YarnBallFibersFollowTwistedStrands)
  EXPECT_EQ(not_fiber, 0u);
  EXPECT_LT(max_radial, 0.05f) << "untwisted fibers follow the sphere";
  // 40 strands of width 0.12 cover a band of 2 pi R x 0.12 each, about 2.4 times the sphere's area in all:
  // crossings leave part of the shell bare, which 300 strands of that width (18 times the area) do not.
  const auto coverage = [&](const VoxelGrid& ball) {
    size_t shell = 0, held = 0;
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
          if (std::abs(glm::length(voxel_centre(ball, i, j, k)) - kYarnBallRadius) < 0.5f * y.strand_radius) {
            ++shell;
            held += ball.voxel_density(i, j, k) > 0.0f;
          }
    return double(held) / double(shell);
  };
  YarnSettings dense = y;
  dense.strands = 300;
  const double sparse_covers = coverage(g), dense_covers = coverage(make_yarn_ball(n, dense));
  EXPECT_GT(sparse_covers, 0.5);
  EXPECT_LT(sparse_covers, dense_covers - 0.1) << dense_covers;
}

TEST(ProceduralVolume, YarnSettingsOutsideTheirRangeThrow) {
  const auto with = [](int strands, float width, float twists) {
    YarnSettings y;
    y.strands = strands;
    y.strand_radius = 0.5f * width;
    y.twists_per_unit = twists;
    return y;
  };
  for (const YarnSettings& y : {with(15, 0.1f, 2), with(0, 0.1f, 2), with(1010, 0.1f, 2), with(40, 0.005f, 2),
                                with(40, 0.5f, 2), with(40, std::nanf(""), 2), with(40, 0.1f, -1),
                                with(40, 0.1f, std::nanf("")), with(40, 0.1f, 65)})
    EXPECT_THROW(make_yarn_ball(16, y), std::invalid_argument) << y.strands << " " << y.strand_radius << " "
                                                                << y.twists_per_unit;
  EXPECT_NO_THROW(make_yarn_ball(16, with(10, 0.4f, 0)));
}

TEST(ProceduralVolume, WovenFabricWarpAndWeft) {
  const int n = 192;
  const VoxelGrid g = make_woven_fabric(n);
  const int ny = g.resolution().y;
  EXPECT_EQ(g.resolution(), Vec3i(n, 8, n));
  EXPECT_FLOAT_EQ(g.lo().x, -1.0f);
  EXPECT_FLOAT_EQ(g.hi().z, 1.0f);
  EXPECT_FLOAT_EQ(g.hi().y, -g.lo().y);
  EXPECT_FLOAT_EQ(g.voxel_size().y, g.voxel_size().x);  // cubic voxels
  EXPECT_FLOAT_EQ(g.voxel_size().z, g.voxel_size().x);
  ASSERT_TRUE(g.has_sggx());
  expect_valid(g, kFabricDensity);

  size_t not_fiber = 0, mid = 0, mid_warp = 0, mid_weft = 0, warp = 0, weft = 0, too_high = 0;
  double warp_along = 0, warp_across = 0, weft_along = 0, weft_across = 0;
  const size_t occupied = for_each_occupied(g, [&](int, int, int, const Vec3& p, float, const Sggx& S) {
    const Vec3 t = fiber_tangent(S, &not_fiber);
    const bool along_x = std::abs(t.x) > std::abs(t.z);
    // The weave's threads stay within |y| ≤ crimp amplitude + half thickness = 0.025.
    too_high += std::abs(p.y) > 0.025f + 0.5f * g.voxel_size().y ? 1 : 0;
    if (std::abs(p.y) < 0.0125f) {
      ++mid;
      (along_x ? mid_warp : mid_weft) += 1;
    }
    if (along_x) {
      ++warp;
      warp_along += std::abs(t.x);
      warp_across += std::abs(t.z);
    } else {
      ++weft;
      weft_along += std::abs(t.z);
      weft_across += std::abs(t.x);
    }
  });
  EXPECT_EQ(not_fiber, 0u);
  EXPECT_EQ(too_high, 0u);
  // About half of the patch's middle layers is thread (48 x 48 crossings, a gap of 10 % between threads).
  EXPECT_GT(occupied, size_t(n) * size_t(n) * size_t(ny) / 8);
  ASSERT_GT(mid, 0u);
  EXPECT_GT(double(mid_warp), 0.3 * double(mid)) << mid_warp << " of " << mid;
  EXPECT_GT(double(mid_weft), 0.3 * double(mid)) << mid_weft << " of " << mid;
  ASSERT_GT(warp, 0u);
  ASSERT_GT(weft, 0u);
  // Crimp and twist lean the fibers away from the thread's axis; the twist alone (the crimp stays in the
  // vertical plane) gives them a horizontal component across the thread.
  EXPECT_LT(warp_along / double(warp), 0.97);
  EXPECT_LT(weft_along / double(weft), 0.97);
  EXPECT_GT(warp_across / double(warp), 0.08);
  EXPECT_GT(weft_across / double(weft), 0.08);

  // Plain weave: at the crossing of weft i (x_i) and warp j (z_j), the warp is on top when i + j is even.
  int right = 0, checked = 0;
  const float h = g.voxel_size().x;
  for (int i = 0; i < 48; ++i)
    for (int j = 0; j < 48; ++j) {
      const float xi = -1.0f + (float(i) + 0.5f) / 24.0f, zj = -1.0f + (float(j) + 0.5f) / 24.0f;
      const int ii = int(std::floor((xi + 1.0f) / h)), kk = int(std::floor((zj + 1.0f) / h));
      // The topmost occupied voxel of the column.
      for (int jj = ny - 1; jj >= 0; --jj) {
        if (g.voxel_density(ii, jj, kk) <= 0.0f) continue;
        size_t dummy = 0;
        const Vec3 t = fiber_tangent(g.voxel_sggx(ii, jj, kk), &dummy);
        const bool warp_on_top = std::abs(t.x) > std::abs(t.z);
        right += warp_on_top == ((i + j) % 2 == 0) ? 1 : 0;
        ++checked;
        break;
      }
    }
  EXPECT_GT(checked, 48 * 48 * 9 / 10);
  EXPECT_GT(right, checked * 95 / 100) << right << " of " << checked;
}

TEST(ProceduralVolume, FabricBoxFollowsResolution) {
  // ny = max(8, ceil(n / 32)), cubic voxels of edge 2 / n: the box is ±ny / n in y.
  for (int n : {8, 64, 384}) {
    const VoxelGrid g = make_woven_fabric(n);
    const int ny = std::max(8, (n + 31) / 32);
    EXPECT_EQ(g.resolution(), Vec3i(n, ny, n)) << n;
    EXPECT_FLOAT_EQ(g.hi().y, float(ny) / float(n)) << n;
    EXPECT_FLOAT_EQ(g.lo().y, -float(ny) / float(n)) << n;
  }
  EXPECT_FLOAT_EQ(make_woven_fabric(384).hi().y, 1.0f / 32.0f);
}

TEST(ProceduralVolume, Deterministic) {
  EXPECT_TRUE(same_bytes(make_smoke_plume(24), make_smoke_plume(24)));
  EXPECT_TRUE(same_bytes(make_yarn_ball(48), make_yarn_ball(48)));
  EXPECT_TRUE(same_bytes(make_woven_fabric(64), make_woven_fabric(64)));
  // And the check can fail: different resolutions differ.
  EXPECT_FALSE(same_bytes(make_smoke_plume(24), make_smoke_plume(25)));
}

TEST(ProceduralVolume, KvoxRoundTrip) {
  test::TempDir dir;
  const std::vector<std::pair<std::string, VoxelGrid>> grids = {
      {"smoke.kvox", make_smoke_plume(16)}, {"yarn.kvox", make_yarn_ball(48)}, {"fabric.kvox", make_woven_fabric(32)}};
  for (const auto& [name, grid] : grids) {
    const fs::path file = dir.path() / name;
    grid.save_kvox(file);
    const VoxelGrid back = VoxelGrid::load(file);
    EXPECT_TRUE(same_bytes(grid, back)) << name;
  }
}

// The smoke as OpenVDB (for Blender, bench/cycles): read back, every occupied voxel's centre holds the same density
// (to 10⁻⁵ of the largest)
// (the file keeps only the occupied voxels, so the box read back is their bounding box). Grids with S are refused.
TEST(ProceduralVolume, VdbRoundTrip) {
  test::TempDir dir;
  const VoxelGrid smoke = make_smoke_plume(24);
  const fs::path file = dir.path() / "smoke.vdb";
  smoke.save_vdb(file);
  const VoxelGrid back = VoxelGrid::load(file);
  const Vec3 size = smoke.voxel_size();
  int occupied = 0, worst = 0;
  double worst_error = 0;
  for (int k = 0; k < smoke.resolution().z; ++k)
    for (int j = 0; j < smoke.resolution().y; ++j)
      for (int i = 0; i < smoke.resolution().x; ++i) {
        const float d = smoke.voxel_density(i, j, k);
        if (d == 0.0f) continue;
        ++occupied;
        const Vec3 centre = smoke.lo() + (Vec3(i, j, k) + 0.5f) * size;
        // Against the largest density: the box read back is rounded in float, so a centre may sit 10⁻⁶ of a voxel
        // off, and a faint voxel beside a dense one takes a little of its neighbour.
        const double error = std::abs(back.density(centre) - d) / smoke.max_density();
        if (error > worst_error) worst_error = error, worst = occupied;
      }
  EXPECT_GT(occupied, 100);
  EXPECT_LT(worst_error, 1e-5) << "occupied voxel " << worst;
  EXPECT_THROW(make_yarn_ball(48).save_vdb(dir.path() / "yarn.vdb"), std::runtime_error);
  EXPECT_FALSE(fs::exists(dir.path() / "yarn.vdb"));
}

TEST(ProceduralVolume, InvalidResolutionThrows) {
  for (int n : {-1, 0, 7, 1025}) {
    EXPECT_THROW(make_smoke_plume(n), std::invalid_argument) << n;
    EXPECT_THROW(make_yarn_ball(n), std::invalid_argument) << n;
    EXPECT_THROW(make_woven_fabric(n), std::invalid_argument) << n;
  }
}

std::string kozu() { return fmt::format("'{}'", test::kozu_binary().string()); }

TEST(ProceduralCommand, WritesFabric) {
  test::TempDir dir;
  const fs::path out = dir.path() / "cloth.kvox";
  std::string log;
  ASSERT_EQ(test::run_command(fmt::format("{} procedural fabric --resolution 48 -o '{}'", kozu(), out.string()), &log),
            0)
      << log;
  EXPECT_NE(log.find("48 x 8 x 48"), std::string::npos) << log;
  // Compact (.kvox version 2) by default: the generator's grid compacted, code for code.
  const VoxelGrid g = VoxelGrid::load(out);
  EXPECT_TRUE(g.is_compact());
  VoxelGrid expected = make_woven_fabric(48);
  expected.compact();
  EXPECT_TRUE(same_bytes(g, expected));
  // --float: version 1, the generator's floats exactly.
  ASSERT_EQ(test::run_command(
                fmt::format("{} procedural fabric --resolution 48 --float -o '{}'", kozu(), out.string()), &log),
            0)
      << log;
  const VoxelGrid f = VoxelGrid::load(out);
  EXPECT_FALSE(f.is_compact());
  EXPECT_TRUE(same_bytes(f, make_woven_fabric(48)));
}

TEST(ProceduralCommand, Errors) {
  test::TempDir dir;
  std::string log;
  // Not .kvox: exit 1, nothing written.
  EXPECT_EQ(
      test::run_command(
          fmt::format("{} procedural fabric --resolution 16 -o '{}/cloth.vdb'", kozu(), dir.path().string()), &log),
      1)
      << log;
  EXPECT_NE(log.find(".kvox"), std::string::npos) << log;
  EXPECT_TRUE(fs::is_empty(dir.path()));
  // Too coarse to hold the threads (an empty grid was written, exit 0): exit 1, the smallest that holds them.
  EXPECT_EQ(
      test::run_command(
          fmt::format("{} procedural fabric --resolution 16 -o '{}/cloth.kvox'", kozu(), dir.path().string()), &log),
      1);
  EXPECT_EQ(log,
            "error: kozu procedural: --resolution 16 is too small to hold the fabric: no voxel is occupied (use at "
            "least 48)\n");
  EXPECT_TRUE(fs::is_empty(dir.path()));
  // Unwritable output: exit 1.
  EXPECT_EQ(test::run_command(fmt::format("{} procedural smoke --resolution 8 -o '{}/no/such/dir/s.kvox'", kozu(),
                                          dir.path().string()),
                              &log),
            1)
      << log;
  // Bad values (unknown kind, resolution out of range) are bad input, exit 1; a missing output is a usage error, 2.
  for (const char* args : {"carpet -o x.kvox", "smoke --resolution 7 -o x.kvox", "yarn --resolution 1025 -o x.kvox"})
    EXPECT_EQ(test::run_command(fmt::format("cd '{}' && {} procedural {}", dir.path().string(), kozu(), args), &log), 1)
        << args << "\n"
        << log;
  EXPECT_EQ(test::run_command(fmt::format("cd '{}' && {} procedural fabric", dir.path().string(), kozu()), &log), 2)
      << log;
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

}  // namespace
}  // namespace kozu
