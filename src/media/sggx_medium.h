// sggx_medium: a microflake medium with the SGGX distribution (Heitz, Dupuy, Crassin, Dachsbacher 2015,
// "The SGGX Microflake Distribution", ACM TOG 34(4), SIGGRAPH 2015).
//
//   σt(ω) = ρ σ(ω)      eq. (2), σ(ω) = sqrt(ωᵀ S ω) eq. (11)
//   σs(ω) = α ρ σ(ω)    eq. (3), α per color channel
//   phase               specular (eq. 24) or diffuse (eq. 25, estimated by eq. 26) microflakes
//   majorant            ρ · sqrt(λmax(S)): bounds σt over all directions
// Homogeneous (SggxMedium): constant ρ and S. Voxel (SggxVoxelMedium, with "file"): ρ and S from a .kvox grid
// with seven channels (`kozu voxelize`, voxel_grid.h), trilinear in ρ and in S's six coefficients, and a
// 3D MIP chain built by averaging ρ and (density-weighted) S (§4.4, §6). Level of detail ("lod"):
//   "auto"  per lookup, from the ray's cone (geometry/ray_cone.h): where the cone is w wide the level is
//           round(log2(w / voxel size)), clamped to the chain, so that a voxel covers about the footprint; camera
//           rays get about one pixel's voxels, rays after a scattering widen with their lobe (and, as the cone's
//           spread divides by the pixel's paths, the image converges to the full-resolution one). Each level has
//           its own majorant grid; tracking splits a ray where its level changes (media/tracking.h).
//   "view"  one level per medium, chosen so that a voxel covers about one pixel where the grid is: with the
//           camera at distance z from the grid's box centre and a pixel subtending the angle a
//           (2 tan(fov/2) / height), the footprint is z·a and the level is round(log2(z·a / voxel size)).
//   int     a fixed level.
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
//   lod            "auto" | "view" | int  "auto"  the MIP level (0 = full resolution), see above
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

// One MIP level of an SGGX voxel grid as a medium, with its own majorant grid (SggxVoxelMedium's levels).
class SggxVoxelLevel final : public Medium {
 public:
  SggxVoxelLevel(const VoxelGrid& grid, float density_scale, const Rgb& albedo, SggxMedium::Phase phase,
                 const MediumTransform& xf)
      : grid_(&grid), scale_(density_scale), albedo_(albedo), phase_(phase), xf_(xf) {}

  MediumProperties properties(const Vec3& p, const Vec3& d) const override;
  const PhaseFunction* phase(const Vec3& p, Arena& arena) const override;
  void majorants(const Vec3& o, const Vec3& d, float t0, float t1, MajorantVisitor& v) const override;
  void build_majorants();  // before the first majorants(); idempotent
  size_t majorant_bytes() const { return majorants_.memory_bytes(); }

 private:
  const VoxelGrid* grid_;  // in SggxVoxelMedium::levels_
  float scale_;
  Rgb albedo_;
  SggxMedium::Phase phase_;
  MediumTransform xf_;  // a similarity
  MajorantGrid majorants_;  // built by build_majorants
};

class SggxVoxelMedium final : public Medium {
 public:
  enum class LodMode { PerLookup, View, Fixed };
  // lod: the level for LodMode::Fixed (ignored otherwise).
  SggxVoxelMedium(const VoxelGrid& grid, float density_scale, const Rgb& albedo, SggxMedium::Phase phase, LodMode mode,
                  int lod = 0, const MediumTransform& xf = {});
  SggxVoxelMedium(const SggxVoxelMedium&) = delete;  // media_ points into levels_
  SggxVoxelMedium& operator=(const SggxVoxelMedium&) = delete;

  // At the level in use: the view's (set_view) or the fixed one; per lookup, the view's for callers without a cone.
  MediumProperties properties(const Vec3& p, const Vec3& d) const override { return current().properties(p, d); }
  const PhaseFunction* phase(const Vec3& p, Arena& arena) const override { return current().phase(p, arena); }
  void majorants(const Vec3& o, const Vec3& d, float t0, float t1, MajorantVisitor& v) const override {
    current().majorants(o, d, t0, t1, v);
  }
  Medium::Lod level_for(float width) const override;
  void set_view(const Vec3& eye, float pixel_width, float pixel_angle) override;
  Stats stats() const override;

  int level() const { return level_; }
  std::string view_warning() const override { return view_warning_; }
  const std::vector<VoxelGrid>& levels() const { return levels_; }
  // The level round(log2(width / voxel size)) a cone of that width (scene units) takes, clamped to the chain.
  int level_of_width(float width) const;

 private:
  void use_level(int level);
  int unclamped_level(float width) const;  // round(log2(width / voxel size)), at least 0
  const SggxVoxelLevel& current() const { return media_[static_cast<size_t>(level_)]; }

  std::vector<VoxelGrid> levels_;
  std::vector<SggxVoxelLevel> media_;  // one per level, over levels_
  LodMode mode_;
  float voxel_ = 0;  // level 0's largest voxel edge, scene units
  int level_ = -1;
  std::string view_warning_;  // set by set_view when the level it asks for is beyond the chain
  MediumTransform xf_;        // a similarity
};

// Reads a "distribution" object (the three forms above) into S.
Sggx read_sggx_distribution(const JsonObject& d);

}  // namespace kozu
