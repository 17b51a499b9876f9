// Tests for the voxel-grid pipeline: VoxelGrid lookups, the .kvox and .vdb readers, the MIP chain, MajorantGrid's
// bounds and DDA, and mesh voxelization. Files are written into a fresh temporary directory per test; the .vdb
// input is produced here with the OpenVDB API, so no binary fixtures live in the repository.
#include "media/majorant_grid.h"
#include "media/sggx_medium.h"
#include "media/voxel_grid.h"
#include "tools/voxelize.h"

#include "core/arena.h"
#include "core/error.h"
#include "core/rng.h"
#include "core/transform.h"
#include "core/warp.h"
#include "media/sggx.h"
#include "support/render_test.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/task_arena.h>
#include <openvdb/openvdb.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

namespace kozu {
namespace {

namespace fs = std::filesystem;

class VoxelFileTest : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(fs::is_directory(dir_)) << dir_; }
  fs::path write(const std::string& name, std::string_view contents) const { return tmp_.write(name, contents); }
  static std::string read(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  // Loads the file expecting an InputError that names it and contains every fragment.
  static void expect_error(const fs::path& path, std::initializer_list<std::string_view> fragments) {
    try {
      const VoxelGrid grid = VoxelGrid::load(path);
      ADD_FAILURE() << "expected an InputError for " << path << ", got " << grid.voxel_count() << " voxels";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), path.string());
      const std::string what = e.what();
      EXPECT_NE(what.find(path.filename().string()), std::string::npos) << what;
      for (std::string_view fragment : fragments)
        EXPECT_NE(what.find(fragment), std::string::npos) << "'" << fragment << "' missing from: " << what;
    }
  }
  test::TempDir tmp_;
  const fs::path& dir_ = tmp_.path();
};

// A random SPD matrix: R diag(λ) Rᵀ with eigenvalues in [lo, hi] (a wide range gives thin or flat flakes).
Sggx random_spd(Pcg32& rng, float lo = 0.01f, float hi = 1.0f) {
  const Vec3 a = glm::normalize(Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f) +
                                Vec3(1e-3f, 0.0f, 0.0f));
  const Vec3 t = glm::normalize(glm::cross(a, std::abs(a.x) > 0.9f ? Vec3(0, 1, 0) : Vec3(1, 0, 0)));
  const Vec3 b = glm::cross(a, t);
  const Vec3 e[3] = {a, t, b};
  Sggx S{0, 0, 0, 0, 0, 0};
  for (const Vec3& v : e) {
    const float l = lo + (hi - lo) * rng.next_float();
    S = S + Sggx{v.x * v.x, v.y * v.y, v.z * v.z, v.x * v.y, v.x * v.z, v.y * v.z} * l;
  }
  return S;
}

bool is_spd(const Sggx& S, double tol = 1e-6) {
  const double m2 = double(S.xx) * S.yy - double(S.xy) * S.xy;
  const double det = S.xx * (double(S.yy) * S.zz - double(S.yz) * S.yz) - S.xy * (double(S.xy) * S.zz - double(S.yz) * S.xz) +
                     S.xz * (double(S.xy) * S.yz - double(S.yy) * S.xz);
  const double scale = std::max({double(S.xx), double(S.yy), double(S.zz)});
  return S.xx > 0 && m2 >= -tol * scale * scale && det >= -tol * scale * scale * scale;
}

void expect_sggx_near(const Sggx& a, const Sggx& b, float tol) {
  EXPECT_NEAR(a.xx, b.xx, tol);
  EXPECT_NEAR(a.yy, b.yy, tol);
  EXPECT_NEAR(a.zz, b.zz, tol);
  EXPECT_NEAR(a.xy, b.xy, tol);
  EXPECT_NEAR(a.xz, b.xz, tol);
  EXPECT_NEAR(a.yz, b.yz, tol);
}

Vec3 voxel_center(const VoxelGrid& g, int i, int j, int k) {
  return g.lo() + (Vec3(float(i), float(j), float(k)) + 0.5f) * g.voxel_size();
}

// ---- lookups ----------------------------------------------------------------------------------------------

TEST(VoxelGrid, TrilinearExactForLinearField) {
  VoxelGrid g(Vec3i(5, 4, 6), Vec3(-1.0f, 0.0f, 0.5f), Vec3(2.0f, 1.0f, 3.5f), true);
  const auto rho = [](const Vec3& p) { return 3.0f + 0.5f * p.x - 0.25f * p.y + 0.75f * p.z; };
  const auto field = [](const Vec3& p) {  // SPD for p in the box
    return Sggx{2.0f + 0.1f * p.x, 2.0f - 0.2f * p.z, 2.5f + 0.3f * p.y, 0.05f * p.x, -0.04f * p.y, 0.03f * p.z};
  };
  for (int k = 0; k < 6; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 5; ++i) g.set_voxel(i, j, k, rho(voxel_center(g, i, j, k)), field(voxel_center(g, i, j, k)));
  // S interpolation is density-weighted; with a linear density it is exact for a constant S only, so the linear
  // S field is checked on a copy with constant density.
  VoxelGrid flat = g;
  for (float& d : flat.density_data()) d = 1.0f;

  Pcg32 rng(7);
  const Vec3 c0 = voxel_center(g, 0, 0, 0), c1 = voxel_center(g, 4, 3, 5);
  for (int n = 0; n < 2000; ++n) {
    const Vec3 u(rng.next_float(), rng.next_float(), rng.next_float());
    const Vec3 p = c0 + u * (c1 - c0);
    EXPECT_NEAR(g.density(p), rho(p), 2e-5f) << n;
    expect_sggx_near(flat.sggx(p), field(p), 2e-6f);
    const VoxelGrid::Lookup both = g.lookup(p);
    EXPECT_EQ(both.density, g.density(p));
    const Sggx s = g.sggx(p);
    EXPECT_EQ(std::memcmp(&both.sggx, &s, sizeof s), 0);
  }
  // Clamp to edge in the outer half voxel, 0 outside the box.
  EXPECT_FLOAT_EQ(g.density(g.lo() + 0.1f * g.voxel_size()), g.voxel_density(0, 0, 0));
  EXPECT_FLOAT_EQ(g.density(g.hi() - 0.1f * g.voxel_size()), g.voxel_density(4, 3, 5));
  EXPECT_EQ(g.density(g.lo() - Vec3(1e-3f, 0.0f, 0.0f)), 0.0f);
  EXPECT_EQ(g.density(g.hi() + Vec3(0.0f, 0.0f, 1e-3f)), 0.0f);
  EXPECT_EQ(g.density(Vec3(std::nanf(""), 0.5f, 1.0f)), 0.0f);
}

TEST(VoxelGrid, SggxExtinctionMatchesLookup) {
  // The fused ρ σ(ω) against ρ(p) sqrt(ωᵀ S(p) ω) from lookup(), on a sparse random grid (half the voxels empty,
  // so the skipped corners are exercised) and at points inside, on and outside the box.
  Pcg32 rng(23);
  VoxelGrid g(Vec3i(6, 5, 4), Vec3(-0.5f, 0.0f, 1.0f), Vec3(1.0f, 2.0f, 2.0f), true);
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 6; ++i)
        g.set_voxel(i, j, k, rng.next_float() < 0.5f ? 0.0f : 4.0f * rng.next_float(), random_spd(rng, 1e-3f, 1.0f));
  const Vec3 extent = g.hi() - g.lo();
  for (int n = 0; n < 5000; ++n) {
    const Vec3 p = g.lo() - 0.1f * extent + 1.2f * extent * Vec3(rng.next_float(), rng.next_float(), rng.next_float());
    const Vec3 w = glm::normalize(Vec3(rng.next_float(), rng.next_float(), rng.next_float()) - 0.5f);
    const VoxelGrid::Lookup l = g.lookup(p);
    const float expected = l.density * sggx::projected_area(l.sggx, w);
    EXPECT_NEAR(g.sggx_extinction(p, w), expected, 1e-5f + 1e-5f * expected) << n;
  }
  EXPECT_EQ(g.sggx_extinction(g.hi() + Vec3(1e-3f), Vec3(0.0f, 0.0f, 1.0f)), 0.0f);
}

TEST(VoxelGrid, EmptyVoxelsDoNotDiluteS) {
  VoxelGrid g(Vec3i(2, 1, 1), Vec3(0.0f), Vec3(2.0f, 1.0f, 1.0f), true);
  const Sggx flake{0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f};  // a surface facing +z
  g.set_voxel(0, 0, 0, 1.0f, flake);
  g.set_voxel(1, 0, 0, 0.0f, Sggx{});  // empty, isotropic placeholder
  for (float x : {0.2f, 0.9f, 1.3f, 1.49f}) {
    expect_sggx_near(g.sggx(Vec3(x, 0.5f, 0.5f)), flake, 1e-7f);
    EXPECT_NEAR(g.density(Vec3(x, 0.5f, 0.5f)), std::clamp(1.5f - x, 0.0f, 1.0f), 1e-6f);
  }
  // Past the last centre only the empty voxel contributes: density 0 and the plain (placeholder) S.
  EXPECT_EQ(g.density(Vec3(1.8f, 0.5f, 0.5f)), 0.0f);
  expect_sggx_near(g.sggx(Vec3(1.8f, 0.5f, 0.5f)), Sggx{}, 1e-7f);
  VoxelGrid empty(Vec3i(2, 1, 1), Vec3(0.0f), Vec3(2.0f, 1.0f, 1.0f), true);
  expect_sggx_near(empty.sggx(Vec3(1.0f, 0.5f, 0.5f)), Sggx{}, 1e-7f);
}

// ---- .kvox ------------------------------------------------------------------------------------------------

// A 7 x 3 x 5 grid with an off-origin box, 30 % empty voxels, random densities and (optionally) random S.
VoxelGrid file_test_grid(Pcg32& rng, bool with_sggx) {
  VoxelGrid g(Vec3i(7, 3, 5), Vec3(-1.25f, 0.1f, 3.0f), Vec3(0.75f, 0.4f, 3.3f), with_sggx);
  for (int k = 0; k < 5; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 7; ++i) {
        const float d = rng.next_float() < 0.3f ? 0.0f : 10.0f * rng.next_float();
        if (with_sggx)
          g.set_voxel(i, j, k, d, random_spd(rng));
        else
          g.set_voxel(i, j, k, d);
      }
  return g;
}

TEST_F(VoxelFileTest, KvoxRoundTripBitExact) {
  Pcg32 rng(11);
  for (const bool with_sggx : {true, false}) {
    VoxelGrid g = file_test_grid(rng, with_sggx);
    const fs::path path = dir_ / (with_sggx ? "s.kvox" : "d.KVOX");
    g.save_kvox(path);
    EXPECT_EQ(fs::file_size(path), 48u + 7u * 3u * 5u * (with_sggx ? 7u : 1u) * 4u);
    EXPECT_EQ(read(path).substr(0, 8), "KOZUVOX1");
    const VoxelGrid r = VoxelGrid::load(path);
    EXPECT_EQ(r.resolution(), g.resolution());
    EXPECT_EQ(std::memcmp(&r.lo(), &g.lo(), sizeof(Vec3)), 0);
    EXPECT_EQ(std::memcmp(&r.hi(), &g.hi(), sizeof(Vec3)), 0);
    ASSERT_EQ(r.has_sggx(), with_sggx);
    EXPECT_EQ(std::memcmp(r.density_data().data(), g.density_data().data(), g.voxel_count() * sizeof(float)), 0);
    if (with_sggx) {
      EXPECT_EQ(std::memcmp(r.sggx_data().data(), g.sggx_data().data(), g.voxel_count() * sizeof(Sggx)), 0);
    }
    // Saving the loaded grid reproduces the file byte for byte.
    const fs::path again = dir_ / "again.kvox";
    r.save_kvox(again);
    EXPECT_EQ(read(again), read(path));
  }
}

// ---- compact storage -------------------------------------------------------------------------------------

// A sparse random SGGX grid in float storage and its compact copy.
std::pair<VoxelGrid, VoxelGrid> float_and_compact(Pcg32& rng) {
  VoxelGrid g(Vec3i(6, 5, 4), Vec3(-0.5f, 0.0f, 1.0f), Vec3(1.0f, 2.0f, 2.0f), true);
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 6; ++i)
        g.set_voxel(i, j, k, rng.next_float() < 0.5f ? 0.0f : 4.0f * rng.next_float(), random_spd(rng, 1e-3f, 1.0f));
  VoxelGrid c = g;
  c.compact();
  return {std::move(g), std::move(c)};
}

TEST(VoxelCompact, VoxelsWithinTheQuantisationBounds) {
  // Each voxel: density within half a step (largest / 65535 / 2) and 0 kept exactly; S within eq. 19's bounds
  // (σ_a within sigma_scale/510, r within 1/254) unless compress_spd had to shrink the correlations, and then
  // still positive definite; 8 bytes per voxel; writing refused.
  Pcg32 rng(41);
  const auto [g, c] = float_and_compact(rng);
  ASSERT_TRUE(c.is_compact());
  EXPECT_EQ(c.memory_bytes(), c.voxel_count() * 8);
  EXPECT_TRUE(c.density_data().empty());
  EXPECT_THROW(VoxelGrid(c).set_voxel(0, 0, 0, 1.0f), std::logic_error);
  const float half_step = g.max_density() / 65535.0f * 0.5f;
  float scale = 0.0f;
  for (size_t idx = 0; idx < g.voxel_count(); ++idx) scale = std::max({scale, g.sggx_at(idx).xx, g.sggx_at(idx).yy, g.sggx_at(idx).zz});
  scale = std::sqrt(scale);
  int shrunk = 0;
  for (size_t idx = 0; idx < g.voxel_count(); ++idx) {
    const float d = g.density_at(idx);
    if (d == 0.0f) {
      EXPECT_EQ(c.density_at(idx), 0.0f);
    }
    EXPECT_NEAR(c.density_at(idx), d, half_step * 1.001f + 1e-7f * d) << idx;
    const Sggx a = g.sggx_at(idx), b = c.sggx_at(idx);
    EXPECT_TRUE(sggx::is_spd(b)) << idx;
    const double sa[3] = {std::sqrt(double(a.xx)), std::sqrt(double(a.yy)), std::sqrt(double(a.zz))};
    const double sb[3] = {std::sqrt(double(b.xx)), std::sqrt(double(b.yy)), std::sqrt(double(b.zz))};
    for (int k = 0; k < 3; ++k) EXPECT_LE(std::abs(sb[k] - sa[k]), scale / 510.0 + 1e-6) << idx;
    const double ra[3] = {a.xy / (sa[0] * sa[1]), a.xz / (sa[0] * sa[2]), a.yz / (sa[1] * sa[2])};
    const double rb[3] = {b.xy / (sb[0] * sb[1]), b.xz / (sb[0] * sb[2]), b.yz / (sb[1] * sb[2])};
    const bool shrinks = !sggx::correlations_pass_guard(sggx::compress(a, scale));
    shrunk += shrinks;
    for (int k = 0; k < 3; ++k) {
      if (!shrinks && std::isfinite(rb[k])) {
        EXPECT_LE(std::abs(rb[k] - ra[k]), 1.0 / 254.0 + 1e-5) << idx;
      }
    }
  }
  std::printf("[ compact ] %d of %zu voxels needed their correlations shrunk\n", shrunk, g.voxel_count());
}

TEST(VoxelCompact, LookupsAreTheFloatLookupsOfTheDecodedVoxels) {
  // The compact grid's lookups (density, S, lookup, and sggx_extinction straight from the codes) against a float
  // grid holding its decoded voxels: the same numbers up to float rounding.
  Pcg32 rng(42);
  const auto [g, c] = float_and_compact(rng);
  VoxelGrid decoded(c.resolution(), c.lo(), c.hi(), true);
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 6; ++i) decoded.set_voxel(i, j, k, c.voxel_density(i, j, k), c.voxel_sggx(i, j, k));
  const Vec3 extent = c.hi() - c.lo();
  for (int n = 0; n < 5000; ++n) {
    const Vec3 p = c.lo() - 0.1f * extent + 1.2f * extent * Vec3(rng.next_float(), rng.next_float(), rng.next_float());
    const Vec3 w = glm::normalize(Vec3(rng.next_float(), rng.next_float(), rng.next_float()) - 0.5f);
    const float de = decoded.density(p);
    EXPECT_NEAR(c.density(p), de, 1e-6f + 1e-6f * de) << n;
    expect_sggx_near(c.sggx(p), decoded.sggx(p), 1e-6f);
    const float e = decoded.sggx_extinction(p, w);
    EXPECT_NEAR(c.sggx_extinction(p, w), e, 1e-5f + 1e-5f * e) << n;
    EXPECT_NEAR(c.lookup(p).density, de, 1e-6f + 1e-6f * de) << n;
  }
  EXPECT_EQ(c.max_density(), decoded.max_density());
}

TEST(VoxelCompact, ThinDistributionsStayPositiveDefinite) {
  // compress_spd on σ = 0.01 surfaces and fibers, whose plain 8-bit correlations are often indefinite: eq. 20
  // alone must give an SPD S, equal to decompress() (whose guard then has nothing to do) to a few ulps.
  Pcg32 rng(43);
  int repaired = 0;
  for (int i = 0; i < 500; ++i) {
    const Vec3 n = warp::square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
    const Sggx s = i % 2 ? sggx::surface(n, 0.01f) : sggx::fiber(n, 0.01f);
    const SggxCompact k = sggx::compress_spd(s);
    repaired += !sggx::correlations_pass_guard(sggx::compress(s));
    ASSERT_TRUE(sggx::correlations_pass_guard(k)) << i;
    const Sggx a = sggx::decompress_unguarded(k, 1.0f), b = sggx::decompress(k, 1.0f);
    EXPECT_TRUE(sggx::is_spd(a)) << i;
    expect_sggx_near(a, b, 1e-6f);  // float against decompress's double: a few ulps
  }
  EXPECT_GT(repaired, 0);  // the case exists
  std::printf("[ compact ] compress_spd repaired %d of 500 thin distributions\n", repaired);
}

TEST_F(VoxelFileTest, KvoxVersion2RoundTripAndErrors) {
  // A compact grid saves as version 2 (8 or 2 bytes per voxel after a 56-byte header) and loads back compact
  // with the same codes; saving it again reproduces the file. Then the v2-specific errors.
  Pcg32 rng(44);
  for (const bool with_sggx : {true, false}) {
    VoxelGrid g = file_test_grid(rng, with_sggx);
    g.compact();
    const fs::path path = dir_ / (with_sggx ? "s2.kvox" : "d2.kvox");
    g.save_kvox(path);
    EXPECT_EQ(fs::file_size(path), 56u + 7u * 3u * 5u * (with_sggx ? 8u : 2u));
    EXPECT_EQ(read(path).substr(0, 8), "KOZUVOX2");
    const VoxelGrid r = VoxelGrid::load(path);
    ASSERT_TRUE(r.is_compact());
    ASSERT_EQ(r.has_sggx(), with_sggx);
    for (size_t idx = 0; idx < g.voxel_count(); ++idx) {
      ASSERT_EQ(r.density_at(idx), g.density_at(idx)) << idx;
      if (with_sggx) expect_sggx_near(r.sggx_at(idx), g.sggx_at(idx), 0.0f);
    }
    const fs::path again = dir_ / "again2.kvox";
    r.save_kvox(again);
    EXPECT_EQ(read(again), read(path));
  }
  const std::string bytes = read(dir_ / "s2.kvox");
  expect_error(write("short2.kvox", bytes.substr(0, 50)), {"truncated .kvox header"});
  expect_error(write("cut2.kvox", bytes.substr(0, bytes.size() - 3)), {"truncated voxel data"});
  std::string step = bytes;
  const float nan = std::nanf("");
  std::memcpy(step.data() + 48, &nan, 4);
  expect_error(write("step2.kvox", step), {"invalid density step"});
  std::string scale = bytes;
  const float zero = 0.0f;
  std::memcpy(scale.data() + 52, &zero, 4);
  expect_error(write("scale2.kvox", scale), {"invalid sigma scale"});
  std::string indefinite = bytes;  // voxel 0's correlations (127, 127, -127): R is singular
  indefinite[56 + 5] = char(127);
  indefinite[56 + 6] = char(127);
  indefinite[56 + 7] = char(-127);
  expect_error(write("r2.kvox", indefinite), {"voxel (0, 0, 0)", "not positive definite"});
}

// A missing showcase volume is named with what makes it: volumes/bush.kvox with scripts/make-volumes.sh, the
// procedural ones (an older scene's volumes/smoke.kvox) with the "procedural" key; any other missing file keeps the
// plain message.
TEST(VoxelGrid, MissingShowcaseVolumeNamesTheScript) {
  test::TempDir dir;
  const auto message = [](const fs::path& p) {
    try {
      VoxelGrid::load(p);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("loaded");
  };
  EXPECT_NE(message(dir.path() / "volumes" / "bush.kvox").find("run scripts/make-volumes.sh"), std::string::npos);
  for (const char* name : {"smoke", "yarn", "fabric"}) {
    const std::string m = message(dir.path() / "volumes" / (std::string(name) + ".kvox"));
    EXPECT_NE(m.find(fmt::format("write \"procedural\": \"{}\" instead of the \"file\"", name)), std::string::npos)
        << m;
  }
  for (const fs::path& p : {dir.path() / "volumes" / "cloud.kvox", dir.path() / "other" / "smoke.kvox"}) {
    const std::string m = message(p);
    EXPECT_EQ(m.find("make-volumes"), std::string::npos) << m;
    EXPECT_NE(m.find("cannot open file"), std::string::npos) << m;
  }
}

TEST_F(VoxelFileTest, KvoxLoadErrors) {
  VoxelGrid g(Vec3i(2, 2, 2), Vec3(0.0f), Vec3(1.0f), true);
  const fs::path good = dir_ / "good.kvox";
  g.save_kvox(good);
  const std::string bytes = read(good);
  ASSERT_EQ(bytes.size(), 48u + 8u * 7u * 4u);

  expect_error(dir_ / "missing.kvox", {"cannot open file"});
  expect_error(write("short.kvox", bytes.substr(0, 30)), {"truncated .kvox header"});
  std::string bad_magic = bytes;
  bad_magic[3] = 'X';
  expect_error(write("magic.kvox", bad_magic), {"bad magic"});
  expect_error(write("truncated.kvox", bytes.substr(0, bytes.size() - 4)), {"truncated voxel data"});
  expect_error(write("trailing.kvox", bytes + "xyz"), {"3 unexpected bytes"});
  std::string channels = bytes;
  channels[20] = 3;
  expect_error(write("channels.kvox", channels), {"unsupported channel count 3"});
  std::string zero = bytes;
  std::memset(zero.data() + 12, 0, 4);
  expect_error(write("zero.kvox", zero), {"empty resolution"});
  std::string huge = bytes;
  std::memset(huge.data() + 8, 0xff, 12);
  expect_error(write("huge.kvox", huge), {"exceeds the limit"});
  std::string box = bytes;
  const float flipped = -1.0f;
  std::memcpy(box.data() + 36, &flipped, 4);  // hi.x < lo.x
  expect_error(write("box.kvox", box), {"invalid box"});
  std::string nan = bytes;
  const float qnan = std::nanf("");
  std::memcpy(nan.data() + 48 + (7 * 3 + 3) * 4, &qnan, 4);  // voxel (1, 1, 0), Szz
  expect_error(write("nan.kvox", nan), {"voxel (1, 1, 0)", "Szz is nan"});
  std::string negative = bytes;
  const float minus = -0.5f;
  std::memcpy(negative.data() + 48 + 7 * 7 * 4, &minus, 4);  // voxel (1, 1, 1), density
  expect_error(write("negative.kvox", negative), {"voxel (1, 1, 1)", "negative density"});
  std::string not_psd = bytes;
  const float big = 3.0f;
  std::memcpy(not_psd.data() + 48 + 4 * 4, &big, 4);  // voxel (0, 0, 0), Sxy with Sxx = Syy = 1
  expect_error(write("psd.kvox", not_psd), {"voxel (0, 0, 0)", "|Sxy|"});
  expect_error(write("grid.raw", bytes), {"unknown voxel grid format '.raw'"});
  EXPECT_NO_THROW(VoxelGrid::load(good));
}

// ---- .vdb -------------------------------------------------------------------------------------------------

TEST_F(VoxelFileTest, VdbDensityAtVoxelCentres) {
  openvdb::initialize();
  const double voxel = 0.5;
  const openvdb::Vec3d translation(1.0, -2.0, 3.0);
  const auto make = [&](const std::string& name, float scale) {
    openvdb::FloatGrid::Ptr g = openvdb::FloatGrid::create(0.0f);
    g->setName(name);
    g->setTransform(openvdb::math::Transform::createLinearTransform(voxel));
    g->transform().postTranslate(translation);
    openvdb::FloatGrid::Accessor acc = g->getAccessor();
    for (int k = 1; k <= 5; ++k)
      for (int j = 0; j <= 3; ++j)
        for (int i = -2; i <= 4; ++i)
          if ((i + j + k) % 3 != 0) acc.setValue(openvdb::Coord(i, j, k), scale * float(1 + i * i + 2 * j + 3 * k));
    return g;
  };
  openvdb::GridPtrVec grids;
  grids.push_back(make("temperature", 100.0f));  // the first float grid, but not the one named "density"
  grids.push_back(make("density", 1.0f));
  const fs::path path = dir_ / "cloud.vdb";
  {
    openvdb::io::File file(path.string());
    file.write(grids);
    file.close();
  }
  const VoxelGrid g = VoxelGrid::load(path);
  // Active bounding box: i in [-2, 4] but (i + j + k) % 3 skips some; the extreme coordinates are all active.
  ASSERT_EQ(g.resolution(), Vec3i(7, 4, 5));
  EXPECT_FALSE(g.has_sggx());
  // lo = world(imin - 0.5), hi = world(imax + 0.5).
  const Vec3 lo(float(-2.5 * voxel + 1.0), float(-0.5 * voxel - 2.0), float(0.5 * voxel + 3.0));
  const Vec3 hi(float(4.5 * voxel + 1.0), float(3.5 * voxel - 2.0), float(5.5 * voxel + 3.0));
  EXPECT_EQ(g.lo(), lo);
  EXPECT_EQ(g.hi(), hi);
  for (int k = 1; k <= 5; ++k)
    for (int j = 0; j <= 3; ++j)
      for (int i = -2; i <= 4; ++i) {
        const float expected = (i + j + k) % 3 != 0 ? float(1 + i * i + 2 * j + 3 * k) : 0.0f;
        EXPECT_EQ(g.voxel_density(i + 2, j, k - 1), expected);
        // The world position of index (i, j, k) is a voxel centre, where trilinear interpolation is exact.
        const Vec3 world(float(i * voxel + 1.0), float(j * voxel - 2.0), float(k * voxel + 3.0));
        EXPECT_NEAR(g.density(world), expected, 1e-4f) << i << " " << j << " " << k;
      }
}

TEST_F(VoxelFileTest, VdbLoadErrors) {
  openvdb::initialize();
  expect_error(dir_ / "missing.vdb", {"cannot open file"});
  expect_error(write("garbage.vdb", "this is not an OpenVDB file at all, just text"),
               {"not a valid OpenVDB file", "bad magic number"});
  {
    openvdb::Vec3SGrid::Ptr velocity = openvdb::Vec3SGrid::create();
    velocity->setName("vel");
    velocity->tree().setValue(openvdb::Coord(0, 0, 0), openvdb::Vec3s(1.0f));
    openvdb::io::File file((dir_ / "vectors.vdb").string());
    file.write({velocity});
    file.close();
  }
  expect_error(dir_ / "vectors.vdb", {"no float grid", "'vel'"});
  {
    openvdb::FloatGrid::Ptr empty = openvdb::FloatGrid::create(0.0f);
    empty->setName("density");
    openvdb::io::File file((dir_ / "empty.vdb").string());
    file.write({empty});
    file.close();
  }
  expect_error(dir_ / "empty.vdb", {"no active voxels"});
  {
    openvdb::FloatGrid::Ptr rotated = openvdb::FloatGrid::create(0.0f);
    rotated->setName("density");
    rotated->tree().setValue(openvdb::Coord(0, 0, 0), 1.0f);
    rotated->transform().postRotate(0.3, openvdb::math::Z_AXIS);
    openvdb::io::File file((dir_ / "rotated.vdb").string());
    file.write({rotated});
    file.close();
  }
  expect_error(dir_ / "rotated.vdb", {"rotated"});
}

// A .vdb cut short anywhere is refused from its header and descriptors before OpenVDB reads it (OpenVDB trusts
// the counts and offsets in a file: cut to its first 100 bytes, it allocated 5 GB and hung). Every prefix of a
// small valid file is tried; each must fail fast with the file's name, and the whole file must load.
TEST_F(VoxelFileTest, VdbTruncatedAnywhereIsRefused) {
  openvdb::initialize();
  {
    openvdb::FloatGrid::Ptr g = openvdb::FloatGrid::create(0.0f);
    g->setName("density");
    for (int i = 0; i < 8; ++i)
      for (int j = 0; j < 8; ++j) g->tree().setValue(openvdb::Coord(i, j, 0), 0.5f);
    openvdb::io::File file((dir_ / "whole.vdb").string());
    file.write({g});
    file.close();
  }
  const std::string bytes = read(dir_ / "whole.vdb");
  EXPECT_EQ(VoxelGrid::load(dir_ / "whole.vdb").voxel_count(), 64u);
  // Every byte of the header and descriptor, then strides through the grid body.
  for (size_t n = 0; n < bytes.size(); n += n < 200 ? 1 : 97) {
    const fs::path cut = write("cut.vdb", bytes.substr(0, n));
    expect_error(cut, {"cut.vdb"});
  }
}

// Two voxels 1000 apart: the active bounding box is 1001^3, which kozu would make dense (4 GB, 31 s before the
// cap): refused at once against VoxelGrid::kMaxVoxels.
TEST_F(VoxelFileTest, VdbSparseFarApartVoxelsHitTheVoxelCap) {
  openvdb::initialize();
  {
    openvdb::FloatGrid::Ptr g = openvdb::FloatGrid::create(0.0f);
    g->setName("density");
    g->tree().setValue(openvdb::Coord(0, 0, 0), 1.0f);
    g->tree().setValue(openvdb::Coord(1000, 1000, 1000), 1.0f);
    openvdb::io::File file((dir_ / "far.vdb").string());
    file.write({g});
    file.close();
  }
  expect_error(dir_ / "far.vdb", {"1001 x 1001 x 1001", "exceeds the limit of 268435456 voxels"});
}

// ---- MIP chain --------------------------------------------------------------------------------------------

double mean_density(const VoxelGrid& g) {
  double sum = 0.0;
  for (float d : g.density_data()) sum += d;
  return sum / double(g.voxel_count());
}

TEST(VoxelMip, MeanDensityPreservedAndSpd) {
  Pcg32 rng(3);
  VoxelGrid g(Vec3i(16, 4, 8), Vec3(0.0f), Vec3(2.0f, 0.5f, 1.0f), true);
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 16; ++i)
        g.set_voxel(i, j, k, rng.next_float() < 0.4f ? 0.0f : rng.next_float(), random_spd(rng, 1e-3f, 1.0f));
  const std::vector<VoxelGrid> chain = build_mip_chain(g);
  ASSERT_EQ(chain.size(), 5u);  // 16x4x8, 8x2x4, 4x1x2, 2x1x1, 1x1x1
  EXPECT_EQ(chain[1].resolution(), Vec3i(8, 2, 4));
  EXPECT_EQ(chain[3].resolution(), Vec3i(2, 1, 1));
  EXPECT_EQ(chain.back().resolution(), Vec3i(1));
  const double mean = mean_density(g);
  for (const VoxelGrid& level : chain) {
    EXPECT_EQ(level.lo(), g.lo());
    EXPECT_EQ(level.hi(), g.hi());
    EXPECT_NEAR(mean_density(level), mean, 1e-6 * mean);
    for (const Sggx& S : level.sggx_data()) EXPECT_TRUE(is_spd(S));
  }
  // One block of level 1 by hand: density mean, S density-weighted.
  float dsum = 0.0f;
  Sggx weighted{0, 0, 0, 0, 0, 0};
  for (int c = 0; c < 8; ++c) {
    const int i = 2 + (c & 1), j = (c >> 1) & 1, k = 4 + ((c >> 2) & 1);
    dsum += g.voxel_density(i, j, k);
    weighted = weighted + g.voxel_sggx(i, j, k) * g.voxel_density(i, j, k);
  }
  EXPECT_NEAR(chain[1].voxel_density(1, 0, 2), dsum / 8.0f, 1e-6f);
  if (dsum > 0.0f) expect_sggx_near(chain[1].voxel_sggx(1, 0, 2), weighted * (1.0f / dsum), 1e-6f);
}

TEST(VoxelMip, ConstantSStaysAndOddSizesClamp) {
  Pcg32 rng(5);
  const Sggx S = random_spd(rng, 0.05f, 0.8f);
  VoxelGrid g(Vec3i(5, 3, 1), Vec3(0.0f), Vec3(1.0f), true);
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 5; ++i) g.set_voxel(i, j, 0, (i + j) % 2 ? 0.0f : 1.0f + float(i), S);
  const std::vector<VoxelGrid> chain = build_mip_chain(g);
  ASSERT_EQ(chain.size(), 4u);  // 5x3x1, 3x2x1, 2x1x1, 1x1x1
  EXPECT_EQ(chain[1].resolution(), Vec3i(3, 2, 1));
  for (const VoxelGrid& level : chain)
    for (const Sggx& s : level.sggx_data()) expect_sggx_near(s, S, 1e-6f);
  // Clamp: level-1 voxel (2, 1) averages fine voxels {4} x {2}, repeated.
  EXPECT_FLOAT_EQ(chain[1].voxel_density(2, 1, 0), g.voxel_density(4, 2, 0));
  // Density-only grids filter too.
  VoxelGrid d(Vec3i(4, 4, 4), Vec3(0.0f), Vec3(1.0f), false);
  for (float& v : d.density_data()) v = rng.next_float();
  const std::vector<VoxelGrid> dchain = build_mip_chain(d);
  ASSERT_EQ(dchain.size(), 3u);
  EXPECT_FALSE(dchain[1].has_sggx());
  EXPECT_NEAR(dchain.back().voxel_density(0, 0, 0), mean_density(d), 1e-6);
}

// ---- majorants --------------------------------------------------------------------------------------------

struct Segment {
  float ta, tb, majorant;
};

std::vector<Segment> walk(const MajorantGrid& m, const Vec3& o, const Vec3& d, float t0, float t1) {
  std::vector<Segment> out;
  m.traverse(o, d, t0, t1, [&](float ta, float tb, float maj) {
    out.push_back({ta, tb, maj});
    return true;
  });
  return out;
}

void check_tiling(const std::vector<Segment>& s, float t0, float t1) {
  ASSERT_FALSE(s.empty());
  EXPECT_EQ(s.front().ta, t0);
  EXPECT_EQ(s.back().tb, t1);
  for (size_t i = 0; i < s.size(); ++i) {
    EXPECT_LE(s[i].ta, s[i].tb) << i;
    if (i > 0) {
      EXPECT_EQ(s[i].ta, s[i - 1].tb) << i;
    }
  }
}

VoxelGrid random_grid(Pcg32& rng, bool with_sggx) {
  VoxelGrid g(Vec3i(13, 10, 9), Vec3(-1.0f, 0.0f, 2.0f), Vec3(1.6f, 1.0f, 2.9f), with_sggx);
  for (int k = 0; k < 9; ++k)
    for (int j = 0; j < 10; ++j)
      for (int i = 0; i < 13; ++i) {
        // Clustered density with empty regions, so cells differ.
        const bool empty = rng.next_float() < 0.3f || (i > 8 && j < 4);
        const float d = empty ? 0.0f : 5.0f * rng.next_float();
        if (with_sggx)
          g.set_voxel(i, j, k, d, random_spd(rng, 1e-4f, 1.0f));
        else
          g.set_voxel(i, j, k, d);
      }
  return g;
}

TEST(MajorantGrid, BoundsInterpolatedExtinctionAlongRays) {
  Pcg32 rng(17);
  for (const int variant : {0, 1, 2}) {  // SGGX, density only, SGGX in compact storage
    const bool with_sggx = variant != 1;
    VoxelGrid g = random_grid(rng, with_sggx);
    if (variant == 2) g.compact();
    const float scale = 2.5f;
    const MajorantGrid m(g, scale, 4);
    EXPECT_EQ(m.resolution(), Vec3i(4, 3, 3));
    const Vec3 extent = g.hi() - g.lo();
    int checked = 0;
    for (int r = 0; r < 300; ++r) {
      // Origins inside and around the box; every 5th ray axis-parallel.
      const Vec3 o = g.lo() - 0.3f * extent + 1.6f * extent * Vec3(rng.next_float(), rng.next_float(), rng.next_float());
      Vec3 d = Vec3(rng.next_float(), rng.next_float(), rng.next_float()) - 0.5f;
      if (r % 5 == 0) {
        d = Vec3(0.0f);
        d[r % 3] = rng.next_float() < 0.5f ? -1.0f : 1.0f;
      }
      d = glm::normalize(d) * (0.5f + rng.next_float());
      const float t0 = r % 2 ? 0.0f : -0.5f, t1 = r % 7 == 0 ? kInfinity : 4.0f;
      const std::vector<Segment> segs = walk(m, o, d, t0, t1);
      check_tiling(segs, t0, t1);
      for (const Segment& s : segs) {
        if (!std::isfinite(s.tb)) continue;
        // Endpoints too, except for the empty segments before and after the box, whose endpoints lie on it.
        const bool outside = s.majorant == 0.0f;
        for (int n = outside ? 1 : 0; n <= (outside ? 31 : 32); ++n) {
          const float t = s.ta + (s.tb - s.ta) * (float(n) / 32.0f);
          const Vec3 p = o + t * d;
          // What tracking evaluates: the fused extinction along the ray (from the codes when compact), against the
          // ray's directional majorant; for density, the interpolated density.
          if (with_sggx) {
            ASSERT_LE(scale * g.sggx_extinction(p, glm::normalize(d)), s.majorant) << "ray " << r << " t " << t;
          } else {
            ASSERT_LE(scale * g.lookup(p).density, s.majorant) << "ray " << r << " t " << t;
          }
          ++checked;
        }
      }
    }
    EXPECT_GT(checked, 10000);
    // An empty grid has zero majorants everywhere.
    VoxelGrid zero(Vec3i(8), Vec3(0.0f), Vec3(1.0f), with_sggx);
    const MajorantGrid mz(zero, 1.0f);
    EXPECT_EQ(mz.max_majorant(), 0.0f);
  }
}

TEST(MediumTransform, SimilarityCheck) {
  EXPECT_TRUE(MediumTransform().is_similarity());
  EXPECT_TRUE(MediumTransform(Transform::translate(Vec3(1, 2, 3)) * Transform::rotate(Vec3(1, 1, 0), 33.0f) *
                              Transform::scale(Vec3(2.5f)))
                  .is_similarity());
  EXPECT_TRUE(MediumTransform(Transform::scale(Vec3(-2.0f, 2.0f, 2.0f))).is_similarity());  // a mirror
  EXPECT_FALSE(MediumTransform(Transform::scale(Vec3(1.0f, 1.0f, 1.01f))).is_similarity());
  Mat4 shear(1.0f);
  shear[1][0] = 0.2f;
  EXPECT_FALSE(MediumTransform(Transform(shear)).is_similarity());
}

TEST(SggxVoxelMedium, TransformTurnsAndPlacesTheFlakes) {
  // The same grid with and without a similarity M = T R s: at the scene image of a local point and direction,
  // the extinction and the (specular, deterministic) phase function equal the local ones, and the
  // majorants still bound the extinction along scene rays.
  Pcg32 rng(29);
  const VoxelGrid g = random_grid(rng, true);
  const Transform rotation = Transform::rotate(Vec3(0.2f, 1.0f, -0.4f), 57.0f);
  const Transform world_from_local =
      Transform::translate(Vec3(-2.0f, 0.5f, 4.0f)) * rotation * Transform::scale(Vec3(2.5f));
  const SggxVoxelMedium local(g, 1.3f, Rgb(0.9f), SggxMedium::Phase::Specular, SggxVoxelMedium::LodMode::Fixed);
  const SggxVoxelMedium placed(g, 1.3f, Rgb(0.9f), SggxMedium::Phase::Specular,
                               SggxVoxelMedium::LodMode::Fixed, 0, MediumTransform(world_from_local));
  Arena arena;
  const Vec3 extent = g.hi() - g.lo();
  const auto random_dir = [&] {
    return glm::normalize(Vec3(rng.next_float(), rng.next_float(), rng.next_float()) - 0.5f);
  };
  int nonzero = 0;
  for (int n = 0; n < 2000; ++n) {
    const Vec3 pl = g.lo() + extent * Vec3(rng.next_float(), rng.next_float(), rng.next_float());
    const Vec3 wl = random_dir(), wo = random_dir(), wi = random_dir();
    const Vec3 p = world_from_local.point(pl);
    const float expected = local.properties(pl, wl).sigma_t.g;
    EXPECT_NEAR(placed.properties(p, rotation.vector(wl)).sigma_t.g, expected, 1e-4f * (1.0f + expected)) << n;
    nonzero += expected > 0.0f;
    const float f_local = local.phase(pl, arena)->eval(wo, wi, rng);
    const float f_placed = placed.phase(p, arena)->eval(rotation.vector(wo), rotation.vector(wi), rng);
    EXPECT_NEAR(f_placed, f_local, 1e-3f * (1.0f + f_local)) << n;
    arena.reset();
  }
  EXPECT_GT(nonzero, 1000);
  // Majorants along scene rays through the placed box.
  for (int r = 0; r < 200; ++r) {
    const Vec3 o = world_from_local.point(g.lo() - 0.3f * extent +
                                          1.6f * extent * Vec3(rng.next_float(), rng.next_float(), rng.next_float()));
    const Vec3 d = random_dir();
    for_each_majorant(placed, o, d, 0.0f, 20.0f, [&](float ta, float tb, float majorant) {
      for (int k = 0; k < 8; ++k) {
        const float t = ta + (tb - ta) * (k + 0.5f) / 8.0f;
        EXPECT_LE(placed.properties(o + t * d, d).sigma_t.g, majorant) << "ray " << r << " t " << t;
      }
      return true;
    });
  }
}

TEST(SggxVoxelMedium, LevelOfDetailFollowsThePixelFootprint) {
  // A 64³ grid over [0, 1]³ (voxel 1/64, centre (0.5, 0.5, 0.5)): level = round(log2(z·a / voxel)), clamped to
  // the 7 levels (64 … 1).
  VoxelGrid g(Vec3i(64), Vec3(0.0f), Vec3(1.0f), true);
  for (float& d : g.density_data()) d = 1.0f;
  SggxVoxelMedium m(g, 1.0f, Rgb(0.8f), SggxMedium::Phase::Diffuse, SggxVoxelMedium::LodMode::View);
  ASSERT_EQ(m.levels().size(), 7u);
  const Vec3 centre(0.5f);
  const float voxel = 1.0f / 64.0f;
  for (const float footprint_in_voxels : {0.3f, 1.0f, 1.3f, 1.5f, 3.0f, 7.9f, 40.0f, 1e4f}) {
    const float z = 10.0f, a = footprint_in_voxels * voxel / z;
    m.set_view(centre + Vec3(0.0f, 0.0f, z), 0.0f, a);
    const int expected =
        footprint_in_voxels <= 1.0f ? 0 : std::min(6, static_cast<int>(std::lround(std::log2(footprint_in_voxels))));
    EXPECT_EQ(m.level(), expected) << footprint_in_voxels;
    EXPECT_EQ(m.stats().lod, expected);
    EXPECT_GT(m.stats().bytes, g.memory_bytes());  // the whole chain stays resident
  }
  // Scaled by 4 in the scene: the same level from 4x the distance.
  SggxVoxelMedium placed(g, 1.0f, Rgb(0.8f), SggxMedium::Phase::Diffuse, SggxVoxelMedium::LodMode::View, 0,
                         MediumTransform(Transform::scale(Vec3(4.0f))));
  m.set_view(centre + Vec3(0.0f, 0.0f, 10.0f), 0.0f, 4.0f * voxel / 10.0f);
  placed.set_view(4.0f * centre + Vec3(0.0f, 0.0f, 40.0f), 0.0f, 4.0f * voxel / 10.0f);
  EXPECT_EQ(m.level(), 2);
  EXPECT_EQ(placed.level(), 2);
  // A fixed level ignores the view.
  SggxVoxelMedium fixed(g, 1.0f, Rgb(0.8f), SggxMedium::Phase::Diffuse, SggxVoxelMedium::LodMode::Fixed, 3);
  fixed.set_view(centre + Vec3(0.0f, 0.0f, 1e3f), 0.0f, 0.1f);
  EXPECT_EQ(fixed.level(), 3);
}

TEST(SggxVoxelMedium, LevelOfDetailPerLookupFollowsTheConeWidth) {
  // Per lookup ("lod": "auto"): a cone of width w takes level round(log2(w / voxel)) (scene units: the grid is
  // scaled by 2), served over [v 2^(l - 1/2), v 2^(l + 1/2)); each level is that MIP level as a medium, and its own
  // majorants bound its extinction along rays.
  Pcg32 rng(31);
  const VoxelGrid g = random_grid(rng, true);  // 13 x 10 x 9: levels 13, 7, 4, 2, 1
  const float scale = 2.0f;
  const SggxVoxelMedium m(g, 1.5f, Rgb(0.7f), SggxMedium::Phase::Diffuse, SggxVoxelMedium::LodMode::PerLookup, 0,
                          MediumTransform(Transform::scale(Vec3(scale))));
  const int levels = static_cast<int>(m.levels().size());
  ASSERT_EQ(levels, 5);
  const Vec3 v = g.voxel_size();
  const float voxel = scale * std::max({v.x, v.y, v.z});
  EXPECT_EQ(m.level_for(0.0f).medium, m.level_for(0.5f * voxel).medium);
  for (int l = 0; l < levels; ++l) {
    const float w = voxel * std::exp2(float(l));
    const Medium::Lod lod = m.level_for(w);
    EXPECT_EQ(m.level_of_width(w), l);
    EXPECT_LE(lod.width_lo, w);
    EXPECT_GT(lod.width_hi, w);
    EXPECT_FLOAT_EQ(lod.width_lo, l == 0 ? 0.0f : voxel * std::exp2(l - 0.5f));
    if (l + 1 < levels) {
      EXPECT_FLOAT_EQ(lod.width_hi, voxel * std::exp2(l + 0.5f));
      EXPECT_EQ(m.level_of_width(lod.width_hi * 1.001f), l + 1);
      EXPECT_NE(m.level_for(lod.width_hi * 1.001f).medium, lod.medium);
    } else {
      EXPECT_EQ(lod.width_hi, kInfinity);
      EXPECT_EQ(m.level_for(1e9f).medium, lod.medium);
    }
    const VoxelGrid& level = m.levels()[size_t(l)];
    const Vec3 extent = scale * (g.hi() - g.lo());
    for (int n = 0; n < 300; ++n) {
      const Vec3 p = scale * g.lo() + extent * Vec3(rng.next_float(), rng.next_float(), rng.next_float());
      const Vec3 d = glm::normalize(Vec3(rng.next_float(), rng.next_float(), rng.next_float()) - 0.5f);
      const float expected = 1.5f * level.sggx_extinction(p / scale, d);
      EXPECT_NEAR(lod.medium->properties(p, d).sigma_t.r, expected, 1e-5f * (1.0f + expected)) << l;
      const Vec3 o = p - 3.0f * d;
      for_each_majorant(*lod.medium, o, d, 0.0f, 6.0f, [&](float ta, float tb, float majorant) {
        for (int k = 0; k < 4; ++k) {
          const float t = ta + (tb - ta) * (k + 0.5f) / 4.0f;
          EXPECT_LE(lod.medium->properties(o + t * d, d).sigma_t.r, majorant) << "level " << l << " t " << t;
        }
        return true;
      });
    }
  }
}

TEST(MajorantGrid, ProductOfMaximaNotMaximumOfProducts) {
  // ρ = 1 with a thin S next to ρ = 0.01 with a large S: between them ρ(p) σmax(S(p)) exceeds both products.
  VoxelGrid g(Vec3i(2, 1, 1), Vec3(0.0f), Vec3(2.0f, 1.0f, 1.0f), true);
  g.set_voxel(0, 0, 0, 1.0f, Sggx{1e-4f, 1e-4f, 1e-4f, 0, 0, 0});
  g.set_voxel(1, 0, 0, 0.01f, Sggx{1e4f, 1e4f, 1e4f, 0, 0, 0});
  const MajorantGrid m(g, 1.0f, 8);
  float worst = 0.0f;
  for (int n = 0; n <= 100; ++n) {
    const VoxelGrid::Lookup l = g.lookup(Vec3(0.5f + float(n) / 100.0f, 0.5f, 0.5f));
    worst = std::max(worst, l.density * sggx::max_projected_area(l.sggx));
  }
  EXPECT_GT(worst, 1.0f);  // both per-voxel products are 0.01 and 1
  EXPECT_LE(worst, m.majorant(0, 0, 0));
}

TEST(MajorantGrid, DirectionalBoundFollowsTheFlakes) {
  // Flakes facing z (a leaf: S = diag(σ², σ², 1)) seen along x have σ(ω) = σ: the directional bound is near that,
  // the isotropic one is 1; along z both are 1, and along a diagonal the bound stays above the true value.
  VoxelGrid g(Vec3i(4), Vec3(0.0f), Vec3(1.0f), true);
  const float sigma = 0.05f;
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) g.set_voxel(i, j, k, 2.0f, sggx::surface(Vec3(0.0f, 0.0f, 1.0f), sigma));
  const MajorantGrid m(g, 1.0f);
  ASSERT_EQ(m.resolution(), Vec3i(5));  // ceil(4.5 / 1)
  const float iso = m.majorant(2, 2, 2);
  EXPECT_NEAR(iso, 2.0f, 1e-3f);
  EXPECT_LE(m.majorant(2, 2, 2, Vec3(1.0f, 0.0f, 0.0f)), 2.0f * 0.07f);  // 2 sqrt(ceil(255 σ²) / 255) = 0.125
  EXPECT_GE(m.majorant(2, 2, 2, Vec3(1.0f, 0.0f, 0.0f)), 2.0f * sigma);
  EXPECT_FLOAT_EQ(m.majorant(2, 2, 2, Vec3(0.0f, 0.0f, -3.0f)), iso);
  const Vec3 diagonal = glm::normalize(Vec3(1.0f, -1.0f, 0.5f));
  EXPECT_GE(m.majorant(2, 2, 2, diagonal), 2.0f * sggx::projected_area(g.voxel_sggx(2, 2, 2), diagonal));
  EXPECT_LT(m.majorant(2, 2, 2, diagonal), iso);
}

TEST(MajorantGrid, SkippingEmptyBlocksKeepsEveryCellsMajorant) {
  // A sparse grid (24 blobs of 4³ voxels) large enough for blocks (41 x 37 x 31 cells, blocks of 8³): along random rays every point's
  // segment carries exactly the majorant of the cell the point lies in (points within 1e-3 of a cell face aside,
  // where rounding may pick either side), so merging empty runs and skipping empty blocks lose no cell.
  Pcg32 rng(41);
  VoxelGrid g(Vec3i(40, 36, 30), Vec3(-1.0f, 0.0f, 0.5f), Vec3(1.0f, 1.5f, 2.0f), true);
  for (int blob = 0; blob < 24; ++blob) {
    const Vec3i c(int(rng.next_float() * 40), int(rng.next_float() * 36), int(rng.next_float() * 30));
    for (int k = std::max(0, c.z - 2); k < std::min(30, c.z + 2); ++k)
      for (int j = std::max(0, c.y - 2); j < std::min(36, c.y + 2); ++j)
        for (int i = std::max(0, c.x - 2); i < std::min(40, c.x + 2); ++i)
          g.set_voxel(i, j, k, 0.5f + rng.next_float(), random_spd(rng, 1e-3f, 1.0f));
  }
  const MajorantGrid m(g, 1.7f);
  ASSERT_EQ(m.resolution(), Vec3i(41, 37, 31));
  const Vec3 cells_per_unit = Vec3(m.resolution()) / (m.hi() - m.lo());
  int checked = 0, nonzero = 0;
  for (int r = 0; r < 400; ++r) {
    const Vec3 extent = g.hi() - g.lo();
    const Vec3 o = g.lo() - 0.3f * extent + 1.6f * extent * Vec3(rng.next_float(), rng.next_float(), rng.next_float());
    const Vec3 d = glm::normalize(Vec3(rng.next_float(), rng.next_float(), rng.next_float()) - 0.5f);
    const std::vector<Segment> segs = walk(m, o, d, 0.0f, 4.0f);
    check_tiling(segs, 0.0f, 4.0f);
    size_t at = 0;
    for (int n = 0; n < 200; ++n) {
      const float t = 4.0f * (n + 0.5f) / 200.0f;
      while (segs[at].tb <= t) ++at;
      const Segment& seg = segs[at];
      const Vec3 c = (o + t * d - m.lo()) * cells_per_unit;
      bool near_face = false, inside = true;
      for (int a = 0; a < 3; ++a) {
        near_face |= std::abs(c[a] - std::round(c[a])) < 1e-3f;
        inside &= c[a] > 0.0f && c[a] < float(m.resolution()[a]);
      }
      if (near_face) continue;
      const float expected = inside ? m.majorant(int(c.x), int(c.y), int(c.z), d) : 0.0f;
      ASSERT_FLOAT_EQ(seg.majorant, expected) << "ray " << r << " t " << t;  // FMA contraction may differ
      ++checked;
      nonzero += expected > 0.0f;
    }
  }
  EXPECT_GT(checked, 20000);
  EXPECT_GT(nonzero, 200) << "the rays should meet the blobs";
}

TEST(MajorantGrid, DdaEdgeCases) {
  VoxelGrid g(Vec3i(16), Vec3(0.0f), Vec3(1.0f), false);
  for (float& d : g.density_data()) d = 1.0f;
  // Dual cells of 8 voxels (1/2) from half a voxel (1/32) before the box: [-1/32, 15/32], [15/32, 31/32], [31/32,
  // 47/32], ceil(16.5 / 8) = 3 per axis.
  const MajorantGrid m(g, 3.0f, 8);
  EXPECT_EQ(m.resolution(), Vec3i(3));
  EXPECT_FLOAT_EQ(m.lo().x, -1.0f / 32.0f);
  EXPECT_FLOAT_EQ(m.hi().x, 47.0f / 32.0f);
  // Along +x through the middle: before the cells, three cells, after them.
  const std::vector<Segment> s = walk(m, Vec3(-1.0f, 0.25f, 0.75f), Vec3(1.0f, 0.0f, 0.0f), 0.0f, 3.0f);
  ASSERT_EQ(s.size(), 5u);
  check_tiling(s, 0.0f, 3.0f);
  EXPECT_EQ(s[0].majorant, 0.0f);
  EXPECT_FLOAT_EQ(s[0].tb, 31.0f / 32.0f);
  EXPECT_FLOAT_EQ(s[1].tb, 47.0f / 32.0f);
  EXPECT_FLOAT_EQ(s[2].tb, 63.0f / 32.0f);
  EXPECT_FLOAT_EQ(s[3].tb, 79.0f / 32.0f);
  for (int c = 1; c <= 3; ++c) EXPECT_GE(s[c].majorant, 3.0f) << c;  // the last cell reads voxel 15 (clamped)
  EXPECT_EQ(s[4].majorant, 0.0f);
  // Misses the box: one empty segment. Parallel to an axis, outside the slab.
  const std::vector<Segment> miss = walk(m, Vec3(-1.0f, 2.0f, 0.5f), Vec3(1.0f, 0.0f, 0.0f), 0.0f, 5.0f);
  ASSERT_EQ(miss.size(), 1u);
  EXPECT_EQ(miss[0].majorant, 0.0f);
  // Starting inside with d = 0: the cell's majorant for the whole interval.
  const std::vector<Segment> still = walk(m, Vec3(0.7f, 0.2f, 0.9f), Vec3(0.0f), 1.0f, 2.0f);
  ASSERT_EQ(still.size(), 1u);
  EXPECT_GT(still[0].majorant, 0.0f);
  // Early stop, empty interval, NaN.
  int calls = 0;
  m.traverse(Vec3(-1.0f, 0.3f, 0.3f), glm::normalize(Vec3(1.0f, 0.5f, 0.4f)), 0.0f, 10.0f, [&](float, float, float) {
    return ++calls < 2;
  });
  EXPECT_EQ(calls, 2);
  calls = 0;
  m.traverse(Vec3(0.5f), Vec3(1.0f, 0.0f, 0.0f), 1.0f, 1.0f, [&](float, float, float) { ++calls; });
  m.traverse(Vec3(std::nanf("")), Vec3(1.0f, 0.0f, 0.0f), 0.0f, 1.0f, [&](float, float, float) { ++calls; });
  EXPECT_EQ(calls, 0);
  // Through a cell corner exactly (diagonal): tiles without gaps.
  check_tiling(walk(m, Vec3(-0.5f), glm::normalize(Vec3(1.0f)), 0.0f, 4.0f), 0.0f, 4.0f);
}

// ---- voxelization -----------------------------------------------------------------------------------------

MeshData unit_cube() {
  MeshData m;
  for (int i = 0; i < 8; ++i) m.positions.emplace_back(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1));
  const uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) m.indices.insert(m.indices.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
  return m;
}

TEST(Voxelize, UnitCubeAreaAndFaceDistribution) {
  constexpr int kN = 16;
  VoxelizeStats stats;
  const VoxelGrid g = voxelize_mesh(unit_cube(), kN, &stats);
  EXPECT_EQ(g.resolution(), Vec3i(kN));
  ASSERT_TRUE(g.has_sggx());
  EXPECT_EQ(stats.triangles, 12u);
  EXPECT_NEAR(stats.mesh_area, 6.0, 1e-12);
  const Vec3 h = g.voxel_size();
  EXPECT_NEAR(h.x, 1.0f / float(kN - 3), 1e-6f);
  double area = 0.0;
  for (float d : g.density_data()) area += double(d) * h.x * h.y * h.z;
  EXPECT_NEAR(area, 6.0, 6e-4);
  EXPECT_NEAR(stats.deposited_area, area, 1e-9);
  // The border voxels are empty.
  for (int k = 0; k < kN; ++k)
    for (int j = 0; j < kN; ++j) {
      EXPECT_EQ(g.voxel_density(0, j, k), 0.0f);
      EXPECT_EQ(g.voxel_density(kN - 1, j, k), 0.0f);
    }
  // The faces lie in the middle of voxel layers 1 and kN - 2 (a 1.5-voxel border). A voxel of a face away from
  // the cube's edges is fully covered by that face alone: density 1/h, and S the face's surface distribution
  // n nᵀ (σ(n) = 1, σ(t) = 0). A voxel on a cube edge holds half a voxel of each of two faces.
  const auto on_layer = [&](int v) { return v == 1 || v == kN - 2; };
  const auto interior = [&](int v) { return v >= 2 && v <= kN - 3; };
  int face_voxels = 0, edge_voxels = 0;
  for (int k = 0; k < kN; ++k)
    for (int j = 0; j < kN; ++j)
      for (int i = 0; i < kN; ++i) {
        const int idx[3] = {i, j, k};
        int layers = 0, normal_axis = -1;
        bool inner = true;
        for (int a = 0; a < 3; ++a) {
          if (on_layer(idx[a])) {
            ++layers;
            normal_axis = a;
          } else if (!interior(idx[a])) {
            inner = false;
          }
        }
        const Sggx& S = g.voxel_sggx(i, j, k);
        if (inner && layers == 1) {
          ++face_voxels;
          EXPECT_NEAR(g.voxel_density(i, j, k) * h.x, 1.0f, 1e-4f);
          for (int a = 0; a < 3; ++a) {
            Vec3 e(0.0f);
            e[a] = 1.0f;
            if (a == normal_axis)
              EXPECT_NEAR(sggx::projected_area(S, e), 1.0f, 1e-5f);
            else
              EXPECT_LT(sggx::projected_area(S, e), 1e-3f);
          }
          EXPECT_NEAR(sggx::projected_area(S, glm::normalize(Vec3(1.0f))), 1.0f / std::sqrt(3.0f), 1e-5f);
        } else if (inner && layers == 2) {
          ++edge_voxels;
          EXPECT_NEAR(g.voxel_density(i, j, k) * h.x, 1.0f, 1e-4f);  // two halves
          int half = 0;
          for (int a = 0; a < 3; ++a) {
            Vec3 e(0.0f);
            e[a] = 1.0f;
            half += std::abs(sggx::projected_area(S, e) - 0.5f) < 1e-4f ? 1 : 0;
          }
          EXPECT_EQ(half, 2);
        }
      }
  EXPECT_EQ(face_voxels, 6 * (kN - 4) * (kN - 4));
  EXPECT_EQ(edge_voxels, 12 * (kN - 4));
}

TEST(Voxelize, TiltedSurfaceAndDeterminism) {
  // A tilted square (two triangles) and an icosahedron-like fan: general-position clipping.
  MeshData m;
  const Vec3 n = glm::normalize(Vec3(0.3f, -0.5f, 0.8f));
  const Vec3 t = glm::normalize(glm::cross(n, Vec3(1.0f, 0.0f, 0.0f))), b = glm::cross(n, t);
  for (const Vec2 uv : {Vec2(-1, -1), Vec2(1, -1), Vec2(1, 1), Vec2(-1, 1)}) m.positions.push_back(uv.x * t + uv.y * b);
  m.indices = {0, 1, 2, 0, 2, 3};
  VoxelizeStats stats;
  const VoxelGrid g = voxelize_mesh(m, 24, &stats);
  EXPECT_NEAR(stats.deposited_area, 4.0, 4e-4);
  EXPECT_NEAR(stats.mesh_area, 4.0, 1e-5);
  size_t occupied = 0;
  for (int k = 0; k < g.resolution().z; ++k)
    for (int j = 0; j < g.resolution().y; ++j)
      for (int i = 0; i < g.resolution().x; ++i) {
        if (g.voxel_density(i, j, k) == 0.0f) continue;
        ++occupied;
        const Sggx& S = g.voxel_sggx(i, j, k);
        EXPECT_NEAR(sggx::projected_area(S, n), 1.0f, 1e-4f);
        EXPECT_LT(sggx::projected_area(S, t), 2e-3f);
        EXPECT_LT(sggx::projected_area(S, b), 2e-3f);
      }
  EXPECT_EQ(occupied, stats.occupied_voxels);

  // Same bits with one thread and with all of them.
  MeshData fan;
  Pcg32 rng(23);
  for (int i = 0; i < 400; ++i) {
    for (int v = 0; v < 3; ++v)
      fan.positions.emplace_back(rng.next_float(), rng.next_float() * 0.6f, rng.next_float() * 0.8f);
    fan.indices.insert(fan.indices.end(), {uint32_t(3 * i), uint32_t(3 * i + 1), uint32_t(3 * i + 2)});
  }
  VoxelizeStats fan_stats;
  const VoxelGrid many = voxelize_mesh(fan, 20, &fan_stats);
  tbb::task_arena one(1);
  const VoxelGrid single = one.execute([&] { return voxelize_mesh(fan, 20); });
  ASSERT_EQ(single.voxel_count(), many.voxel_count());
  EXPECT_EQ(std::memcmp(single.density_data().data(), many.density_data().data(), many.voxel_count() * sizeof(float)), 0);
  EXPECT_EQ(std::memcmp(single.sggx_data().data(), many.sggx_data().data(), many.voxel_count() * sizeof(Sggx)), 0);
  EXPECT_NEAR(fan_stats.deposited_area, fan_stats.mesh_area, 1e-4 * fan_stats.mesh_area);
}

TEST_F(VoxelFileTest, VoxelizedGridsPassTheLoader) {
  // Estimated S (often rank 1: a single flat face) must satisfy the loader's checks after a round trip.
  MeshData tilted;
  const Vec3 n = glm::normalize(Vec3(-0.2f, 0.7f, 0.4f));
  const Vec3 t = glm::normalize(glm::cross(n, Vec3(0.0f, 0.0f, 1.0f))), b = glm::cross(n, t);
  for (const Vec2 uv : {Vec2(-1, -1), Vec2(1, -1), Vec2(1, 1), Vec2(-1, 1)}) tilted.positions.push_back(uv.x * t + uv.y * b);
  tilted.indices = {0, 1, 2, 0, 2, 3};
  for (const MeshData& mesh : {unit_cube(), tilted}) {
    const VoxelGrid g = voxelize_mesh(mesh, 12);
    const fs::path path = dir_ / "mesh.kvox";
    g.save_kvox(path);
    const VoxelGrid r = VoxelGrid::load(path);
    EXPECT_EQ(std::memcmp(r.sggx_data().data(), g.sggx_data().data(), g.voxel_count() * sizeof(Sggx)), 0);
  }
}

TEST(Voxelize, RejectsBadInput) {
  EXPECT_THROW(voxelize_mesh(MeshData{}, 16), std::invalid_argument);
  EXPECT_THROW(voxelize_mesh(unit_cube(), 3), std::invalid_argument);
  MeshData degenerate;
  degenerate.positions = {Vec3(0.0f), Vec3(1.0f), Vec3(2.0f)};
  degenerate.indices = {0, 1, 2};
  EXPECT_THROW(voxelize_mesh(degenerate, 16), std::invalid_argument);
  MeshData point;
  point.positions = {Vec3(1.0f), Vec3(1.0f), Vec3(1.0f)};
  point.indices = {0, 1, 2};
  EXPECT_THROW(voxelize_mesh(point, 16), std::invalid_argument);
}

}  // namespace
}  // namespace kozu
