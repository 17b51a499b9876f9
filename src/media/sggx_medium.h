// sggx_medium: a microflake medium with the SGGX distribution (Heitz, Dupuy, Crassin, Dachsbacher 2015,
// "The SGGX Microflake Distribution", ACM TOG 34(4), SIGGRAPH 2015).
//
//   σt(ω) = ρ σ(ω)      eq. (2), σ(ω) = sqrt(ωᵀ S ω) eq. (11)
//   σs(ω) = α ρ σ(ω)    eq. (3), α per color channel
//   phase               specular (eq. 24) or diffuse (eq. 25, estimated by eq. 26) microflakes
//   majorant            ρ · sqrt(λmax(S)): bounds σt over all directions
// Homogeneous (SggxMedium): constant ρ and S. Voxel (SggxVoxelMedium, with "file"): ρ and S from a .kvox grid
// with seven channels (`kozu voxelize`, voxel_grid.h), trilinear in ρ and in S's six coefficients, and a
// 3D MIP chain built by averaging ρ and (density-weighted) S (§4.4, §6). Level of detail: one level per
// medium, chosen so that a voxel covers about one pixel where the grid is: with the camera at distance z from
// the grid's box centre and a pixel subtending the angle a (2 tan(fov/2) / height), the footprint is z·a and
// the level is round(log2(z·a / voxel size)), clamped to the chain. "lod" overrides it with a fixed level.
//
// Parameters (homogeneous)
//   density       float   1          ≥ 0    ρ, the flakes' area density per scene unit³
//   albedo        rgb     0.8        [0, 1] α
//   phase         string  "specular" "specular" | "diffuse"
//   distribution  object  required   {"kind": "surface", "normal": n, "roughness": σ}  (eqs. 13–14)
//                                    {"kind": "fiber", "tangent": t, "roughness": σ}  (eqs. 15–16)
//                                    {"S": [Sxx, Syy, Szz, Sxy, Sxz, Syz]}            (eq. 10; positive definite)
// Parameters (voxel)
//   file           string  required   a .kvox grid with density and S (7 channels)
//   density_scale  float   1          multiplies ρ
//   albedo, phase  as above
//   lod            "auto" | int  "auto"  the MIP level (0 = full resolution)
//   transform      object  identity   places the grid: rotation, uniform scale, translation (medium_transform.h);
//                                     the flakes turn with the grid, density stays per scene unit
#pragma once

#include "media/majorant_grid.h"
#include "media/medium.h"
#include "media/medium_transform.h"
#include "media/sggx.h"
#include "media/voxel_grid.h"

#include <vector>

namespace kozu {

class JsonObject;

class SggxMedium final : public Medium {
 public:
  enum class Phase { Specular, Diffuse };
  SggxMedium(float density, const Rgb& albedo, const Sggx& S, Phase phase);
  static Deferred<Medium> parse(const JsonObject& desc);

  MediumProperties properties(const Vec3& p, const Vec3& d) const override;
  const PhaseFunction* phase(const Vec3& p, Arena& arena) const override;
  void majorants(const Vec3& o, const Vec3& d, float t0, float t1, MajorantVisitor& v) const override;

 private:
  float density_;
  Rgb albedo_;
  Sggx S_;
  Phase phase_;
  float majorant_;
};

class SggxVoxelMedium final : public Medium {
 public:
  // lod < 0: automatic (set_view).
  SggxVoxelMedium(const VoxelGrid& grid, float density_scale, const Rgb& albedo, SggxMedium::Phase phase, int lod,
                  const MediumTransform& xf = {});

  MediumProperties properties(const Vec3& p, const Vec3& d) const override;
  const PhaseFunction* phase(const Vec3& p, Arena& arena) const override;
  void majorants(const Vec3& o, const Vec3& d, float t0, float t1, MajorantVisitor& v) const override;
  void set_view(const Vec3& eye, float pixel_width, float pixel_angle) override;
  Stats stats() const override;

  int level() const { return level_; }
  std::string view_warning() const override { return view_warning_; }
  const std::vector<VoxelGrid>& levels() const { return levels_; }

 private:
  void use_level(int level);

  std::vector<VoxelGrid> levels_;
  float scale_;
  Rgb albedo_;
  SggxMedium::Phase phase_;
  bool auto_lod_;
  int level_ = -1;
  std::string view_warning_;  // set by set_view when the level it asks for is beyond the chain
  MajorantGrid majorants_;
  MediumTransform xf_;  // a similarity
};

// Reads a "distribution" object (the three forms above) into S.
Sggx read_sggx_distribution(const JsonObject& d);

}  // namespace kozu
