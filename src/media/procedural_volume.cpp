// procedural_volume: smoke plume, yarn ball and woven fabric voxel volumes (procedural_volume.h).
#include "media/procedural_volume.h"

#include "core/rng.h"
#include "media/sggx.h"

#include <fmt/format.h>
#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

namespace kozu {

using namespace procedural;

namespace {

void check_resolution(const char* what, int n) {
  if (n < kMinResolution || n > kMaxResolution)
    throw std::invalid_argument(
        fmt::format("{}: resolution {} outside [{}, {}]", what, n, kMinResolution, kMaxResolution));
}

// Runs f(i, j, k) for every voxel, z slices in parallel.
template <class F>
void for_each_voxel(const Vec3i& res, F&& f) {
  tbb::parallel_for(0, res.z, [&](int k) {
    for (int j = 0; j < res.y; ++j)
      for (int i = 0; i < res.x; ++i) f(i, j, k);
  });
}

float smoothstep(float e0, float e1, float x) {
  const float t = std::clamp((x - e0) / (e1 - e0), 0.0f, 1.0f);
  return t * t * (3.0f - 2.0f * t);
}

// ---- twisted plies (shared by the yarn ball and the fabric) --------------------------------------------

// Ply layout in a strand's cross-section, relative to the strand's radius (semi-axes for an ellipse): two
// plies whose centres sit kPlyOffset from the axis, of radius kPlyRadius, so that they fill the strand
// (offset + radius = 1) and overlap slightly at the axis, as pressed plies do.
constexpr float kPlyOffset = 0.45f;
constexpr float kPlyRadius = 0.55f;

// Density at relative distance ρ from a ply's centre: a solid core fading smoothly to 0 at the ply's edge.
float ply_density(float peak, float rho) { return peak * (1.0f - smoothstep(0.4f, 1.0f, rho)); }

// The nearer of the two plies to the cross-section point (u, v) (in units of the strand's semi-axes) when
// the plies are at twist angle theta: which ply (0: at angle theta, 1: at theta + π), its relative distance
// ρ, and cos/sin of its angle.
struct PlyHit {
  float rho;
  float cos_t, sin_t;
};
PlyHit nearest_ply(float u, float v, float theta) {
  const float c = std::cos(theta), s = std::sin(theta);
  const float d0 = sqr(u - kPlyOffset * c) + sqr(v - kPlyOffset * s);
  const float d1 = sqr(u + kPlyOffset * c) + sqr(v + kPlyOffset * s);
  if (d0 <= d1) return {std::sqrt(d0) / kPlyRadius, c, s};
  return {std::sqrt(d1) / kPlyRadius, -c, -s};
}

// ---- smoke ----------------------------------------------------------------------------------------------

constexpr uint64_t kSmokeSeed = 3;
constexpr int kNoiseTableSize = 4096;  // power of two: the hash is masked

class ValueNoise {
 public:
  explicit ValueNoise(uint64_t seed) {
    Pcg32 rng(seed);
    for (float& v : table_) v = rng.next_float();
  }
  // Trilinear interpolation (smoothstep-weighted) of hashed lattice values, in [0, 1).
  float operator()(float x, float y, float z) const {
    const float fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
    const int i = static_cast<int>(fx), j = static_cast<int>(fy), k = static_cast<int>(fz);
    const float wx = smoothstep(0.0f, 1.0f, x - fx), wy = smoothstep(0.0f, 1.0f, y - fy),
                wz = smoothstep(0.0f, 1.0f, z - fz);
    float acc = 0.0f;
    for (int dk = 0; dk < 2; ++dk)
      for (int dj = 0; dj < 2; ++dj)
        for (int di = 0; di < 2; ++di) {
          const float w = (di ? wx : 1 - wx) * (dj ? wy : 1 - wy) * (dk ? wz : 1 - wz);
          acc += w * hash(i + di, j + dj, k + dk);
        }
    return acc;
  }

 private:
  float hash(int i, int j, int k) const {
    const uint32_t h = (static_cast<uint32_t>(i) * 73856093u) ^ (static_cast<uint32_t>(j) * 19349663u) ^
                       (static_cast<uint32_t>(k) * 83492791u);
    return table_[h & (kNoiseTableSize - 1)];
  }
  std::array<float, kNoiseTableSize> table_{};
};

// ---- yarn ball ------------------------------------------------------------------------------------------

constexpr uint64_t kYarnSeed = 5;

struct Strand {
  Vec3 axis, e1, e2;  // right-handed: e1 × e2 = axis; the centreline is radius (cos φ e1 + sin φ e2)
  float phase;        // twist angle at φ = 0
  float radius;       // of the centreline
};

// The strands are wound in bands, as a ball is wound by hand: a band is kYarnWindingsPerBand successive
// windings whose axes turn by one strand diameter (2 Rs / R rad) about a direction w ⟂ the band's axis, so
// they lie side by side (except near ±w, where all great circles of the band meet) and the band reads as a
// ribbon of parallel strands; band axes and w are random (fixed seed).
static_assert(kYarnStrands % kYarnWindingsPerBand == 0);
// Strands lie pressed flat on the ball: an elliptical cross-section of half width Rs (along the circle's axis)
// and half thickness kYarnFlatness · Rs (radially). Winding i's centreline has radius
// R + (1 − kYarnFlatness) Rs (2 i / (N − 1) − 1): later windings lie further out and cover earlier ones where
// they cross, as on a real ball, and every strand stays within |r − R| ≤ Rs.
constexpr float kYarnFlatness = 0.7f;

std::vector<Strand> make_strands(const YarnSettings& settings) {
  Pcg32 rng(kYarnSeed);
  std::vector<Strand> strands;
  const int count = settings.strands;
  strands.reserve(size_t(count));
  const float step = 2.0f * settings.strand_radius / kYarnBallRadius;
  for (int band = 0; band < count / kYarnWindingsPerBand; ++band) {
    const float z = 1.0f - 2.0f * rng.next_float(), phi = kTwoPi * rng.next_float();
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    const Vec3 A(r * std::cos(phi), r * std::sin(phi), z);
    const Vec3 b1 = glm::normalize(glm::cross(A, std::abs(A.x) > 0.9f ? Vec3(0, 1, 0) : Vec3(1, 0, 0)));
    const Vec3 b2 = glm::cross(A, b1);
    const float psi = kTwoPi * rng.next_float();
    const Vec3 w = std::cos(psi) * b1 + std::sin(psi) * b2;
    for (int k = 0; k < kYarnWindingsPerBand; ++k) {
      const float delta = (float(k) - 0.5f * float(kYarnWindingsPerBand - 1)) * step;
      Strand s;
      s.axis = glm::normalize(std::cos(delta) * A + std::sin(delta) * glm::cross(w, A));
      s.e1 = glm::normalize(glm::cross(s.axis, std::abs(s.axis.x) > 0.9f ? Vec3(0, 1, 0) : Vec3(1, 0, 0)));
      s.e2 = glm::cross(s.axis, s.e1);
      s.phase = kTwoPi * rng.next_float();
      const float order = 2.0f * float(strands.size()) / float(count - 1) - 1.0f;  // count >= 10 (make_yarn_ball)
      s.radius = kYarnBallRadius + (1.0f - kYarnFlatness) * settings.strand_radius * order;
      strands.push_back(s);
    }
  }
  return strands;
}

// ---- woven fabric ---------------------------------------------------------------------------------------

// 24 threads per unit: 48 across the 2-unit patch, 8 voxels per thread spacing at the default n = 384.
constexpr float kThreadsPerUnit = 24.0f;
constexpr float kThreadSpacing = 1.0f / kThreadsPerUnit;
constexpr int kThreadCount = 48;
// Half width 0.45 spacings: a gap of a tenth of the spacing lets neighbouring threads read separately.
constexpr float kThreadHalfWidth = 0.45f * kThreadSpacing;
// Half thickness 2/3 of the half width: threads in a weave are flattened (2.4 voxels at n = 384).
constexpr float kThreadHalfThickness = 0.0125f;
// Crimp amplitude = half thickness: warp and weft centres are 2 half thicknesses apart at a crossing, so
// the threads touch there.
constexpr float kCrimpAmplitude = kThreadHalfThickness;
// Half height of the box: holds the weave's |y| ≤ amplitude + half thickness = 0.025 with a margin of more
// than one voxel at n = 384, where n · h = 12 is an integer so that the box is exactly ±h.
constexpr float kFabricHalfHeight = 1.0f / 32.0f;
// Ply twist along the threads, as for the yarn.
constexpr float kFabricTwistsPerUnit = 8.0f;

struct ThreadHit {
  float rho = 2.0f;    // relative distance to the nearer ply's centre; ≥ 1 outside every ply
  Vec3 tangent{0.0f};  // in the thread's local (s, y, w) coordinates
};

// One thread in its local coordinates: s along the thread, w across it (horizontal), y up, right-handed
// (s, y, w). Centreline y_c(s) = sign · A cos(π (s − s0) / spacing); cross-section an ellipse of semi-axes
// (half width, half thickness) in the plane spanned by W = (0, 0, 1) and V = (−y_c', 1, 0) / |·|, the normal
// of the centreline in the (s, y) plane. Ply k's centre: P(s) = C(s) + a r_p cos θ_k W + b r_p sin θ_k V(s),
// θ_k = 2π f s + phase + kπ; the fiber tangent is dP/ds.
ThreadHit thread_ply(float s, float y, float w, float sign, float phase) {
  constexpr float a = kThreadHalfWidth, b = kThreadHalfThickness, A = kCrimpAmplitude;
  constexpr float k = kPi / kThreadSpacing;
  constexpr float twist_rate = kTwoPi * kFabricTwistsPerUnit;  // dθ/ds
  const float xi = k * (s - (-1.0f + 0.5f * kThreadSpacing));
  const float cos_xi = std::cos(xi), sin_xi = std::sin(xi);
  const float yc = sign * A * cos_xi;
  const float dy = -sign * A * k * sin_xi;       // y_c'
  const float ddy = -sign * A * k * k * cos_xi;  // y_c''
  const float g = 1.0f / std::sqrt(1.0f + dy * dy);
  const float u = w / a;
  const float v = (y - yc) * g / b;  // distance along V, to first order in the curvature
  ThreadHit hit;
  if (u * u + v * v >= 1.0f) return hit;
  const PlyHit ply = nearest_ply(u, v, twist_rate * s + phase);
  if (ply.rho >= 1.0f) return hit;
  hit.rho = ply.rho;
  const Vec3 V = g * Vec3(-dy, 1.0f, 0.0f);
  const float dg = -dy * ddy * g * g * g;
  const Vec3 dV = dg * Vec3(-dy, 1.0f, 0.0f) + g * Vec3(-ddy, 0.0f, 0.0f);
  const Vec3 dP = Vec3(1.0f, dy, 0.0f) + (a * kPlyOffset * twist_rate * -ply.sin_t) * Vec3(0.0f, 0.0f, 1.0f) +
                  (b * kPlyOffset) * (twist_rate * ply.cos_t * V + ply.sin_t * dV);
  hit.tangent = glm::normalize(dP);
  return hit;
}

// Twist phase of thread `index` of a family (0: warp, 1: weft), from a hash: threads are not in step.
float thread_phase(int family, int index) {
  return kTwoPi * u32_to_unit_float(hash_combine(hash_u32(0x6661627u + uint32_t(family)), uint32_t(index)));
}

}  // namespace

VoxelGrid make_smoke_plume(int n) {
  check_resolution("make_smoke_plume", n);
  VoxelGrid grid(Vec3i(n), Vec3(-1.0f, 0.0f, -1.0f), Vec3(1.0f, 2.0f, 1.0f), false);
  const ValueNoise noise(kSmokeSeed);
  const float inv_n = 1.0f / float(n);
  for_each_voxel(grid.resolution(), [&](int i, int j, int k) {
    // x, z in [-1, 1]; eta = height / 2 in [0, 1] (the plume's shape is defined on the unit height).
    const float x = (float(i) + 0.5f) * inv_n * 2.0f - 1.0f;
    const float eta = (float(j) + 0.5f) * inv_n;
    const float z = (float(k) + 0.5f) * inv_n * 2.0f - 1.0f;
    // A plume widening with height, its axis swirled by a height-dependent offset.
    const float cx = 0.15f * std::sin(5.0f * eta), cz = 0.15f * std::cos(4.0f * eta);
    const float r = std::hypot(x - cx, z - cz) / (0.2f + 0.5f * eta);
    if (r >= 1.0f) return;
    // 4 octaves of value noise (weights 1, 1/2, 1/4, 1/8, normalised by their sum 1.875), drifting upwards.
    float f = 0.0f, scale = 4.0f, weight = 1.0f;
    for (int octave = 0; octave < 4; ++octave, scale *= 2.0f, weight *= 0.5f)
      f += weight * noise(scale * x, scale * eta - 3.0f * eta, scale * z);
    f /= 1.875f;
    const float d = (1.0f - r) * std::max(0.0f, f - 0.35f) * 2.5f * std::sqrt(std::max(0.0f, 1.0f - eta));
    if (d > 0.0f) grid.set_voxel(i, j, k, d);
  });
  return grid;
}

VoxelGrid make_yarn_ball(int n, const YarnSettings& settings) {
  check_resolution("make_yarn_ball", n);
  if (settings.strands < kYarnWindingsPerBand || settings.strands > kYarnMaxStrands ||
      settings.strands % kYarnWindingsPerBand != 0)
    throw std::invalid_argument(fmt::format("make_yarn_ball: {} strands: expected a multiple of {} in [{}, {}]",
                                            settings.strands, kYarnWindingsPerBand, kYarnWindingsPerBand,
                                            kYarnMaxStrands));
  if (!(settings.strand_radius >= 0.5f * kYarnMinStrandWidth && settings.strand_radius <= 0.5f * kYarnMaxStrandWidth))
    throw std::invalid_argument(fmt::format("make_yarn_ball: strand width {} outside [{}, {}]",
                                            2.0f * settings.strand_radius, kYarnMinStrandWidth, kYarnMaxStrandWidth));
  if (!(settings.twists_per_unit >= 0.0f && settings.twists_per_unit <= kYarnMaxTwists))
    throw std::invalid_argument(
        fmt::format("make_yarn_ball: {} twists per unit outside [0, {}]", settings.twists_per_unit, kYarnMaxTwists));
  VoxelGrid grid(Vec3i(n), Vec3(-1.0f), Vec3(1.0f), true);
  const std::vector<Strand> strands = make_strands(settings);
  const float R = kYarnBallRadius, Rs = settings.strand_radius;
  const float a = Rs, b = kYarnFlatness * Rs;  // semi-axes: along the circle's axis, radial
  // Whole twists per great circle, ≈ twists_per_unit per unit length.
  const float twists = std::round(kTwoPi * R * settings.twists_per_unit);
  const float inv_n = 1.0f / float(n);
  for_each_voxel(grid.resolution(), [&](int i, int j, int k) {
    const Vec3 p = (Vec3(float(i), float(j), float(k)) + 0.5f) * inv_n * 2.0f - 1.0f;
    if (std::abs(glm::length(p) - R) >= Rs) return;
    // Last-wound strand first: the first whose ply holds p lies on top.
    for (auto it = strands.rbegin(); it != strands.rend(); ++it) {
      const Strand& st = *it;
      const float along = glm::dot(p, st.axis);
      if (std::abs(along) >= a) continue;
      const Vec3 q = p - along * st.axis;
      const float ql = glm::length(q);
      // Cross-section coordinates in units of the semi-axes: u outwards (radial in the circle's plane),
      // v along the axis.
      const float u = (ql - st.radius) / b, v = along / a;
      if (u * u + v * v >= 1.0f) continue;
      const float phi = std::atan2(glm::dot(q, st.e2), glm::dot(q, st.e1));
      const PlyHit ply = nearest_ply(u, v, twists * phi + st.phase);
      if (ply.rho >= 1.0f) continue;
      // Ply centre P(φ) = (R_i + b r_p cos θ) ê + a r_p sin θ axis with θ = m φ + phase: its helix tangent
      // dP/dφ = (R_i + b r_p cos θ) T + m r_p (a cos θ axis − b sin θ ê), T = dê/dφ = axis × ê.
      const Vec3 e = q / ql;
      const Vec3 T = glm::cross(st.axis, e);
      const Vec3 dP = (st.radius + b * kPlyOffset * ply.cos_t) * T +
                      (twists * kPlyOffset) * (a * ply.cos_t * st.axis - b * ply.sin_t * e);
      // rho just below 1 can round the density to 0: such a voxel stays empty (with the default S).
      const float density = ply_density(kYarnDensity, ply.rho);
      if (density > 0.0f)
        grid.set_voxel(i, j, k, density, sggx::fiber(glm::normalize(dP), kFiberRoughness));  // eq. (16)
      return;
    }
  });
  return grid;
}

namespace {

// The fabric's slab: n × ny × n cubic voxels.
int fabric_thickness(int n) { return std::max(8, static_cast<int>(std::ceil(float(n) * kFabricHalfHeight))); }

}  // namespace

VoxelGrid make_woven_fabric(int n) {
  check_resolution("make_woven_fabric", n);
  const int ny = fabric_thickness(n);
  const float half_y = float(ny) / float(n);  // voxels of edge 2/n
  VoxelGrid grid(Vec3i(n, ny, n), Vec3(-1.0f, -half_y, -1.0f), Vec3(1.0f, half_y, 1.0f), true);
  std::array<float, kThreadCount> warp_phase{}, weft_phase{};
  for (int t = 0; t < kThreadCount; ++t) {
    warp_phase[size_t(t)] = thread_phase(0, t);
    weft_phase[size_t(t)] = thread_phase(1, t);
  }
  const float h = 2.0f / float(n);
  // The thread whose centre is nearest to c in [-1, 1] (threads are narrower than their spacing, so only
  // that one can hold the point).
  auto nearest = [](float c) { return std::clamp(int(std::floor((c + 1.0f) * kThreadsPerUnit)), 0, kThreadCount - 1); };
  auto centre = [](int t) { return -1.0f + (float(t) + 0.5f) * kThreadSpacing; };
  for_each_voxel(grid.resolution(), [&](int i, int j, int k) {
    const float x = -1.0f + (float(i) + 0.5f) * h, y = -half_y + (float(j) + 0.5f) * h;
    const float z = -1.0f + (float(k) + 0.5f) * h;
    // Warp j along x at z_j, up at the crossings with weft i where i + j is even; weft i along z at x_i,
    // down there: y_warp(x_i) = (−1)^(i+j) A = −y_weft(z_j).
    const int wa = nearest(z), we = nearest(x);
    const float warp_sign = (wa % 2 == 0) ? 1.0f : -1.0f, weft_sign = (we % 2 == 0) ? -1.0f : 1.0f;
    // Local (s, y, w) frames, right-handed: warp (x, y, z); weft (z, y, −x).
    const ThreadHit warp = thread_ply(x, y, z - centre(wa), warp_sign, warp_phase[size_t(wa)]);
    const ThreadHit weft = thread_ply(z, y, centre(we) - x, weft_sign, weft_phase[size_t(we)]);
    if (warp.rho >= 1.0f && weft.rho >= 1.0f) return;
    const bool use_warp = warp.rho <= weft.rho;
    const ThreadHit& hit = use_warp ? warp : weft;
    const Vec3 t = use_warp ? hit.tangent : Vec3(-hit.tangent.z, hit.tangent.y, hit.tangent.x);
    const float density = ply_density(kFabricDensity, hit.rho);
    if (density > 0.0f) grid.set_voxel(i, j, k, density, sggx::fiber(t, kFiberRoughness));  // eq. (16)
  });
  return grid;
}

namespace {

VoxelGrid make_default_yarn_ball(int n) { return make_yarn_ball(n); }

constexpr ProceduralVolumeKind kKinds[] = {
    {"smoke", &make_smoke_plume, 64, false},
    {"yarn", &make_default_yarn_ball, 192, true},
    {"fabric", &make_woven_fabric, 384, true},
};

}  // namespace

std::span<const ProceduralVolumeKind> procedural_volume_kinds() { return kKinds; }

const ProceduralVolumeKind* find_procedural_volume(std::string_view name) {
  for (const ProceduralVolumeKind& k : kKinds)
    if (name == k.name) return &k;
  return nullptr;
}

VoxelSource read_voxel_source(const JsonObject& desc) {
  VoxelSource src;
  const bool file = desc.has("file"), proc = desc.has("procedural");
  if (file && proc) desc.fail("procedural", "give either \"file\" or \"procedural\", not both");
  if (!proc) {
    src.file = desc.get_path("file");  // names the missing key when neither is given
    return src;
  }
  const std::string name = desc.get_enum("procedural", {"smoke", "yarn", "fabric"});
  src.kind = find_procedural_volume(name);
  src.resolution = desc.get_int("resolution", src.kind->default_resolution,
                                Range::closed(procedural::kMinResolution, procedural::kMaxResolution));
  if (name == "yarn") {
    YarnSettings& y = src.yarn;
    y.strands = desc.get_int("strands", kYarnStrands, Range::closed(kYarnWindingsPerBand, kYarnMaxStrands));
    if (y.strands % kYarnWindingsPerBand != 0)
      desc.fail("strands", fmt::format("{}: expected a multiple of {} (the strands are wound in bands of {})",
                                       y.strands, kYarnWindingsPerBand, kYarnWindingsPerBand));
    y.strand_radius =
        0.5f * desc.get_float("strand_width", 2.0f * kYarnStrandRadius,
                              Range::closed(kYarnMinStrandWidth, kYarnMaxStrandWidth));
    y.twists_per_unit = desc.get_float("twists", kYarnTwistsPerUnit, Range::closed(0.0, kYarnMaxTwists));
  }
  return src;
}

VoxelGrid VoxelSource::load(const JsonObject& desc) const {
  try {
    if (kind) {
      const int n = resolution;
      const Vec3i dims = std::string_view(kind->name) == "fabric" ? Vec3i(n, fabric_thickness(n), n) : Vec3i(n);
      check_voxel_grid_memory(fmt::format("procedural {} at resolution {}", kind->name, n), dims, kind->sggx);
      return std::string_view(kind->name) == "yarn" ? make_yarn_ball(resolution, yarn) : kind->make(resolution);
    }
    return VoxelGrid::load(file);
  } catch (const InputError& e) {
    desc.fail(key(), e.what());
  } catch (const std::exception& e) {  // a generator's refusal, or memory
    desc.fail(key(), e.what());
  }
}

}  // namespace kozu
