#include "media/grid_medium.h"

#include "media/procedural_volume.h"

#include "core/error.h"
#include "core/json_reader.h"
#include "media/homogeneous.h"

namespace kozu {

namespace {
constexpr int kVoxelsPerMajorantCell = 4;  // grid_medium.h
}  // namespace

GridMedium::GridMedium(VoxelGrid grid, float density_scale, const Rgb& albedo, float g, const MediumTransform& xf)
    : grid_(std::move(grid)),
      scale_(density_scale),
      albedo_(albedo),
      phase_(g),
      majorants_(grid_, density_scale, kVoxelsPerMajorantCell),
      xf_(xf) {}

MediumProperties GridMedium::properties(const Vec3& p, const Vec3&) const {
  const float sigma_t = scale_ * grid_.density(xf_.point(p));
  return {Rgb(sigma_t), albedo_ * sigma_t};
}

void GridMedium::majorants(const Vec3& o, const Vec3& d, float t0, float t1, MajorantVisitor& v) const {
  majorants_.traverse(xf_.point(o), xf_.vector(d), t0, t1,
                      [&](float a, float b, float m) { return v.segment(a, b, m); });
}

Deferred<Medium> GridMedium::parse(const JsonObject& desc) {
  const VoxelSource source = read_voxel_source(desc);
  const float scale = desc.get_float("density_scale", 1.0f, Range::non_negative());
  const Rgb albedo = desc.get_rgb("albedo", Rgb(0.8f), Range::unit());
  const float g = read_hg_phase(desc);
  const bool compact = desc.get_enum("storage", {"compact", "float"}, "compact") == "compact";
  const MediumTransform xf =
      desc.has("transform") ? MediumTransform(read_transform(desc.get_object("transform"))) : MediumTransform();
  return Deferred<Medium>([=]() -> std::unique_ptr<Medium> {
    VoxelGrid grid = source.load(desc);
    if (compact) grid.compact();
    return std::make_unique<GridMedium>(std::move(grid), scale, albedo, g, xf);
  });
}

}  // namespace kozu
