#include "media/sggx_medium.h"

#include "media/procedural_volume.h"

#include "core/error.h"
#include "core/json_reader.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace kozu {

SggxMedium::SggxMedium(float density, const Rgb& albedo, const Sggx& S, Phase phase)
    : density_(density), albedo_(albedo), S_(S), phase_(phase), majorant_(density * sggx::max_projected_area(S)) {}

MediumProperties SggxMedium::properties(const Vec3&, const Vec3& d) const {
  const float sigma_t = density_ * sggx::projected_area(S_, d);  // eq. (2)
  return {Rgb(sigma_t), albedo_ * sigma_t};                      // eq. (3)
}

const PhaseFunction* SggxMedium::phase(const Vec3&, Arena& arena) const {
  if (phase_ == Phase::Specular) return arena.make<SggxSpecularPhase>(S_);
  return arena.make<SggxDiffusePhase>(S_);
}

void SggxMedium::majorants(const Vec3&, const Vec3&, float t0, float t1, MajorantVisitor& v) const {
  v.segment(t0, t1, majorant_);
}

Sggx read_sggx_distribution(const JsonObject& d) {
  Sggx S;
  if (d.has("S")) {
    const JsonArray a = d.get_array("S");
    if (a.size() != 6) a.fail("expected [Sxx, Syy, Szz, Sxy, Sxz, Syz]");
    S = {a.number(0), a.number(1), a.number(2), a.number(3), a.number(4), a.number(5)};
    if (!sggx::is_spd(S)) d.fail("S", "the matrix must be symmetric positive definite");
  } else {
    const std::string kind = d.get_enum("kind", {"surface", "fiber"});
    const float roughness = d.get_float("roughness", {}, Range{0.0, 1.0, true, false});
    if (kind == "surface") {
      S = sggx::surface(d.get_direction("normal"), roughness);
    } else {
      S = sggx::fiber(d.get_direction("tangent"), roughness);
    }
  }
  d.finish();
  return S;
}

Deferred<Medium> SggxMedium::parse(const JsonObject& desc) {
  const Rgb albedo = desc.get_rgb("albedo", Rgb(0.8f), Range::unit());
  const Phase phase =
      desc.get_enum("phase", {"specular", "diffuse"}, "specular") == "specular" ? Phase::Specular : Phase::Diffuse;
  if (desc.has("file") || desc.has("procedural")) {
    const VoxelSource source = read_voxel_source(desc);
    const float scale = desc.get_float("density_scale", 1.0f, Range::non_negative());
    const bool compact = desc.get_enum("storage", {"compact", "float"}, "compact") == "compact";
    int lod = 0;
    SggxVoxelMedium::LodMode mode = SggxVoxelMedium::LodMode::PerLookup;
    if (desc.has("lod") && !desc.raw("lod").is_string()) {
      lod = desc.get_int("lod", {}, Range::at_least(0));
      mode = SggxVoxelMedium::LodMode::Fixed;
    } else if (desc.has("lod") && desc.get_enum("lod", {"auto", "view"}) == "view") {
      mode = SggxVoxelMedium::LodMode::View;
    }
    MediumTransform xf;
    if (desc.has("transform")) {
      xf = MediumTransform(read_transform(desc.get_object("transform")));
      if (!xf.is_similarity())
        desc.fail("transform",
                  "an SGGX volume takes rotations, uniform scales and translations only (a non-uniform "
                  "scale or shear would reshape its microflakes)");
    }
    return Deferred<Medium>([=]() -> std::unique_ptr<Medium> {
      VoxelGrid grid = source.load(desc);
      if (!grid.has_sggx())
        desc.fail(source.key(), "the grid has no SGGX channels (make one with `kozu voxelize`, or use the "
                                "procedural yarn or fabric)");
      if (compact) grid.compact();  // every MIP level then is compact too
      auto medium = std::make_unique<SggxVoxelMedium>(grid, scale, albedo, phase, mode, lod, xf);
      const int levels = static_cast<int>(medium->levels().size());
      if (mode == SggxVoxelMedium::LodMode::Fixed && lod >= levels) {
        const Vec3i r = grid.resolution();
        desc.fail("lod", fmt::format("level {} does not exist: the {} x {} x {} grid has levels 0 to {}", lod, r.x, r.y,
                                     r.z, levels - 1));
      }
      return medium;
    });
  }
  const float density = desc.get_float("density", 1.0f, Range::non_negative());
  const Sggx S = read_sggx_distribution(desc.get_object("distribution"));
  return std::make_unique<SggxMedium>(density, albedo, S, phase);
}

// ---- voxel ---------------------------------------------------------------------------------------------

MediumProperties SggxVoxelLevel::properties(const Vec3& p, const Vec3& d) const {
  const float sigma_t = scale_ * grid_->sggx_extinction(xf_.point(p), xf_.direction(d));  // eq. (2)
  return {Rgb(sigma_t), albedo_ * sigma_t};                                                // eq. (3)
}

const PhaseFunction* SggxVoxelLevel::phase(const Vec3& p, Arena& arena) const {
  const Sggx local = grid_->sggx(xf_.point(p));
  const Sggx S = xf_.identity() ? local : sggx::rotated(local, xf_.rotation());
  if (phase_ == SggxMedium::Phase::Specular) return arena.make<SggxSpecularPhase>(S);
  return arena.make<SggxDiffusePhase>(S);
}

void SggxVoxelLevel::majorants(const Vec3& o, const Vec3& d, float t0, float t1, MajorantVisitor& v) const {
  majorants_.traverse(xf_.point(o), xf_.vector(d), t0, t1,
                      [&](float a, float b, float m) { return v.segment(a, b, m); });
}

void SggxVoxelLevel::build_majorants() {
  if (majorants_.empty()) majorants_ = MajorantGrid(*grid_, scale_);
}

SggxVoxelMedium::SggxVoxelMedium(const VoxelGrid& grid, float density_scale, const Rgb& albedo, SggxMedium::Phase phase,
                                 LodMode mode, int lod, const MediumTransform& xf)
    : levels_(build_mip_chain(grid)), mode_(mode), xf_(xf) {
  media_.reserve(levels_.size());
  for (const VoxelGrid& l : levels_) media_.emplace_back(l, density_scale, albedo, phase, xf);
  const Vec3 v = levels_[0].voxel_size();
  voxel_ = std::max({v.x, v.y, v.z}) * xf.scale();
  // Per lookup every level serves some cone, so every level needs its majorants.
  if (mode_ == LodMode::PerLookup)
    for (SggxVoxelLevel& m : media_) m.build_majorants();
  // A fixed level beyond the chain is the caller's error (parse() reports it); keep the coarsest here.
  use_level(mode_ == LodMode::Fixed ? std::clamp(lod, 0, static_cast<int>(levels_.size()) - 1) : 0);
}

void SggxVoxelMedium::use_level(int level) {
  level_ = level;
  media_[static_cast<size_t>(level)].build_majorants();
}

int SggxVoxelMedium::unclamped_level(float width) const {
  return width > voxel_ ? static_cast<int>(std::lround(std::log2(width / voxel_))) : 0;
}

int SggxVoxelMedium::level_of_width(float width) const {
  return std::min(unclamped_level(width), static_cast<int>(levels_.size()) - 1);
}

Medium::Lod SggxVoxelMedium::level_for(float width) const {
  if (mode_ != LodMode::PerLookup) return {&current(), 0.0f, kInfinity};
  const int level = level_of_width(width);
  const int coarsest = static_cast<int>(levels_.size()) - 1;
  // round(log2(w / v)) = level for w in [v 2^(level - 1/2), v 2^(level + 1/2)).
  const float lo = level == 0 ? 0.0f : voxel_ * std::exp2(static_cast<float>(level) - 0.5f);
  const float hi = level == coarsest ? kInfinity : voxel_ * std::exp2(static_cast<float>(level) + 0.5f);
  return {&media_[static_cast<size_t>(level)], lo, hi};
}

void SggxVoxelMedium::set_view(const Vec3& eye, float pixel_width, float pixel_angle) {
  if (mode_ == LodMode::Fixed) return;
  const VoxelGrid& base = levels_[0];
  const float distance = glm::length(xf_.scale() * (0.5f * (base.lo() + base.hi()) - xf_.point(eye)));
  const float footprint = pixel_width + distance * pixel_angle;  // a camera ray cone's width there, scene units
  const int level = unclamped_level(footprint);
  const int coarsest = static_cast<int>(levels_.size()) - 1;
  use_level(std::clamp(level, 0, coarsest));
  // Beyond the chain, a coarsest voxel is still smaller than a pixel: the grid spans a few pixels and aliases.
  view_warning_.clear();
  if (level > coarsest) {
    const Vec3 extent = (base.hi() - base.lo()) * xf_.scale();
    view_warning_ = fmt::format(
        "medium '{}': the level of detail is clamped: the view asks for level {}, the grid's coarsest is {} (the grid "
        "spans about {:.1f} pixels, so its detail aliases; render it larger or closer, or fix \"lod\")",
        name, level, coarsest, std::max({extent.x, extent.y, extent.z}) / footprint);
  }
}

Medium::Stats SggxVoxelMedium::stats() const {
  Stats s;
  s.lod = level_;
  for (const VoxelGrid& l : levels_) s.bytes += l.memory_bytes();  // the whole chain stays resident
  for (const SggxVoxelLevel& m : media_) s.majorant_bytes += m.majorant_bytes();
  s.lod_mode = mode_ == LodMode::PerLookup ? "auto" : mode_ == LodMode::View ? "view" : "fixed";
  return s;
}

}  // namespace kozu
