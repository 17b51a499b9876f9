// procedural_volume: deterministic procedural voxel volumes for kozu's showcase scenes (`kozu procedural`),
// returned as VoxelGrid (voxel_grid.h; written as .kvox). They replace tools/make_procedural_volumes.py.
//
// Fiber-like flakes. The yarn and fabric volumes store SGGX matrices (Heitz, Dupuy, Crassin & Dachsbacher
// 2015, "The SGGX Microflake Distribution", ACM TOG 34(4)) of a fiber-like
// distribution about the local fiber tangent t (eqs. 15–16, sggx::fiber):
//     S = σ² t tᵀ + (I − t tᵀ) = I − (1 − σ²) t tᵀ,   eigenvalues (1, 1, σ²), σ = kFiberRoughness = 0.2,
// so the flakes' normals lie about the plane ⟂ t, as on a cylinder. Each voxel holds one fiber: its centre is
// sampled (no supersampling, which would blend orientations into a non-fiber S). Empty voxels have density 0
// and the default S = Sggx{}.
//
// Twisted plies. A yarn strand or a cloth thread has an elliptical cross-section (semi-axes a, b) holding two
// plies twisted about the centreline. In the cross-section, in units of the semi-axes, ply k's centre is at
// kPlyOffset (cos θ_k, sin θ_k), θ_k = 2π f s + φ + kπ (arc parameter s, twist rate f, a per-strand phase φ),
// and the ply is a disc of radius kPlyRadius about it (offset + radius = 1: the plies fill the strand and
// overlap slightly at its axis); where both plies hold a point the nearer centre wins. The fiber tangent is the
// ply's helix tangent dP/ds, the exact derivative of the ply centre curve P(s) = C(s) + a r_p cos θ_k N1(s) +
// b r_p sin θ_k N2(s) (including the turning of the centreline and its normals), so the flakes lean against
// the strand direction by the twist angle, as in real twisted yarn. Density inside a ply is
// peak · (1 − smoothstep(0.4, 1, ρ)), ρ = distance to the ply centre / ply radius (a solid core with a smooth
// edge), 0 outside.
//
// Generators. Each is parallel over z slices (oneTBB) and computes every voxel independently from its centre,
// so the result is identical for any thread count. The resolution n must lie in [8, 1024], else
// std::invalid_argument.
//   make_smoke_plume(n)   density only, n³ voxels over (-1, 0, -1)–(1, 2, 1): a rising plume widening with
//                         height, its axis swirled by a height-dependent offset, modulated by 4-octave fBm
//                         value noise (a 4096-entry table from a fixed-seed Pcg32) and fading towards the top.
//                         Densities in [0, 2.5] (scenes scale them).
//   make_yarn_ball(n, s)  density + S, n³ voxels over (-1, -1, -1)–(1, 1, 1): kYarnStrands strands wound on
//                         great circles of the sphere of radius kYarnBallRadius, in bands of 10 side-by-side
//                         windings (random band axes, fixed seed), as a ball is wound by hand. Strands are
//                         pressed flat (half width kYarnStrandRadius = 5 voxels across at the default n = 192,
//                         half thickness 0.7 of that) and later windings lie slightly further out
//                         (centreline radii spread over ±0.3 strand radii), so they cover earlier ones where
//                         they cross; all density lies within |r − kYarnBallRadius| ≤ kYarnStrandRadius.
//                         2 plies, about 8 twists per unit length (a whole number per circle: no seam), peak
//                         density kYarnDensity. Only voxels in that shell are tested, and a strand only where
//                         |p · axis| < its half width.
//   make_woven_fabric(n)  density + S, n × ny × n voxels over x, z in [-1, 1], y in [-ny/n, ny/n] (cubic
//                         voxels of edge 2/n), ny = max(8, ceil(n / 32)): a plain-weave patch, warp threads
//                         along x, weft along z, 24 threads per unit length each way (48 across); elliptical
//                         threads going over and under the crossing threads as a sinusoid in y; 2 twisted
//                         plies per thread, their helices following the sinusoid's slope; peak density
//                         kFabricDensity. Sizes are named constants in procedural_volume.cpp.
#pragma once

#include "core/json_reader.h"
#include "media/voxel_grid.h"

#include <filesystem>
#include <span>
#include <string_view>

namespace kozu {

namespace procedural {

// Roughness σ of the fiber-like flakes (eq. 15): eigenvalues of S are (1, 1, σ²).
inline constexpr float kFiberRoughness = 0.2f;
// Peak flake density of a ply (flake area per unit volume). The yarn ball is a single layer of yarn standing
// for a whole ball: at 3x the cloth's density one layer has an optical depth of about 4, so the ball reads as
// solid; the thin cloth's scene scales its density instead.
inline constexpr float kYarnDensity = 180.0f;
inline constexpr float kFabricDensity = 60.0f;
// Yarn ball: radius of the sphere the strands are wound on, the strands' half width, their number.
inline constexpr float kYarnBallRadius = 0.8f;
inline constexpr float kYarnStrandRadius = 0.026f;
inline constexpr int kYarnStrands = 300;
// Twists per unit length of strand (rounded so that each great circle holds a whole number of twists).
inline constexpr float kYarnTwistsPerUnit = 8.0f;
// Strands per band of side-by-side windings: a yarn ball's strand count is a multiple of it.
inline constexpr int kYarnWindingsPerBand = 10;
// Accepted yarn settings (YarnSettings below).
inline constexpr int kYarnMaxStrands = 1000;
inline constexpr float kYarnMinStrandWidth = 0.01f, kYarnMaxStrandWidth = 0.4f;
inline constexpr float kYarnMaxTwists = 64.0f;
// Accepted resolutions.
inline constexpr int kMinResolution = 8;
inline constexpr int kMaxResolution = 1024;

}  // namespace procedural

VoxelGrid make_smoke_plume(int n);
// The yarn ball's shape. A medium with "procedural": "yarn" may set them: "strands" (a multiple of 10, in [10,
// 1000]), "strand_width" (the strand's full width in the grid's units, where the ball's radius is 0.8; in
// [0.01, 0.4]) and "twists" (ply twists per unit length, in [0, 64]). The defaults are the constants above; a ball
// seen small (about 150 pixels across) reads as yarn with fewer, wider strands and a slower twist, whose
// structure is not finer than the pixels.
struct YarnSettings {
  int strands = procedural::kYarnStrands;
  float strand_radius = procedural::kYarnStrandRadius;  // half width
  float twists_per_unit = procedural::kYarnTwistsPerUnit;
};
VoxelGrid make_yarn_ball(int n, const YarnSettings& settings = {});
VoxelGrid make_woven_fabric(int n);

// The generators by name ("smoke", "yarn", "fabric"), with their default resolutions (64, 192, 384): what
// `kozu procedural` writes and what a medium's "procedural" key generates at load.
struct ProceduralVolumeKind {
  const char* name;
  VoxelGrid (*make)(int);
  int default_resolution;
  bool sggx;  // holds SGGX matrices (yarn, fabric), else density only
};
std::span<const ProceduralVolumeKind> procedural_volume_kinds();
const ProceduralVolumeKind* find_procedural_volume(std::string_view name);  // null when unknown

// Where a grid or sggx medium's voxels come from: "file" (a .kvox or .vdb), or "procedural": KIND with an optional
// "resolution" (generated at load, in well under a second at the defaults: no file needed).
struct VoxelSource {
  std::filesystem::path file;
  const ProceduralVolumeKind* kind = nullptr;
  int resolution = 0;
  YarnSettings yarn;  // "procedural": "yarn" only
  std::string key() const { return kind ? "procedural" : "file"; }
  // The grid; failures are reported through desc at key() (desc.fail throws).
  VoxelGrid load(const JsonObject& desc) const;
};
// Reads "file" or "procedural" (+ "resolution", and the yarn's "strands", "strand_width", "twists") from desc;
// exactly one of "file" and "procedural" must be present.
VoxelSource read_voxel_source(const JsonObject& desc);

}  // namespace kozu
