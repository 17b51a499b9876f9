// Shapes: the geometry Embree intersects, plus what shading and area lights need from it.
#pragma once

#include "geometry/interaction.h"

#include <embree3/rtcore.h>

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace kozu {

class Medium;

// Opacity cut-outs (a material's "opacity", materials/opacity_mask.h): the probability that a ray stops where it
// meets the surface at texture coordinates uv. The accelerator asks it for every candidate hit of a shape that
// has one (geometry/embree_scene.h); it must be safe to call from any thread and must not throw.
class OpacityMask {
 public:
  virtual ~OpacityMask() = default;
  virtual float opacity(const Vec2& uv) const = 0;
};

// A point sampled on a shape's surface, with its density per unit area.
struct AreaSample {
  Vec3 p;
  Vec3 n;  // unit geometric normal, front side
  float pdf_area = 0;
};

class Shape {
 public:
  virtual ~Shape() = default;

  // Adds this shape as one Embree geometry and returns its geometry id.
  virtual unsigned attach(RTCDevice device, RTCScene scene) const = 0;
  // Fills the interaction for a hit found by Embree: barycentric u, v of primitive prim and
  // Embree's unnormalised geometric normal (same orientation as kozu's front side).
  virtual void interaction(const Ray& ray, float t, uint32_t prim, float u, float v, const Vec3& ng,
                           SurfaceInteraction& si) const = 0;
  virtual size_t primitive_count() const = 0;
  virtual float primitive_area(uint32_t prim) const = 0;
  // Grows [lo, hi] to include the shape (callers start from an empty box); for the scene's bounding sphere.
  virtual void bounds(Vec3& lo, Vec3& hi) const = 0;
  // dp/du and dp/dv at the hit (the (u, v) conventions of docs/scene-format.md), for texture footprints. Zero
  // where (u, v) is degenerate (a triangle whose texture coordinates are collinear, a sphere's poles).
  virtual void uv_derivatives(const SurfaceInteraction& si, Vec3* dpdu, Vec3* dpdv) const = 0;
  // The tangent frame normal maps are given in (materials/normal_map.h): xyz the unit tangent along dp/du,
  // perpendicular to si.shading.n, and w = ±1 its handedness, so that the bitangent is b = w · cross(n, t) (w = −1
  // where the texture is mirrored). A zero xyz where (u, v) is degenerate (a sphere's poles).
  virtual Vec4 tangent(const SurfaceInteraction& si) const = 0;
  // The surface's curvature at the hit for ray cones (geometry/ray_cone.h), seen from the front side (ng): > 0
  // where the surface bulges towards ng. Of the shading normals, so a smooth-shaded mesh curves like the surface
  // it approximates.
  virtual float curvature(const SurfaceInteraction& si) const = 0;
  // Texture coordinates of a candidate hit (Embree's barycentric u, v on primitive prim at distance t along ray),
  // without a full interaction: for opacity lookups inside the accelerator.
  virtual Vec2 hit_uv(const Ray& ray, float t, uint32_t prim, float u, float v) const = 0;
  // Computes what tangent() needs and the shape does not have yet (a mesh's per-vertex tangents); called once,
  // before rendering, for shapes whose material has a normal or bump map.
  virtual void prepare_tangents() {}
  // Animated shapes (scene/animation.h): places the geometry as loaded (kept on the first call) by `pose`, a
  // rotation, positive scale and translation, then `refresh` hands the moved geometry to Embree's geometry `geom`
  // (the scene is committed by the caller).
  virtual void set_pose(const Mat4& pose) = 0;
  virtual void refresh(RTCGeometry geom) const = 0;
  // Edges on one triangle only (matched by position, so UV seams do not open a mesh); 0 for a closed surface.
  // A shape that bounds a medium or a subsurface material should be closed (the loader warns).
  virtual size_t open_edges() const = 0;

  const Material* material = nullptr;
  // The material's opacity cut-out (null: opaque). The accelerator installs a filter on shapes that have one.
  const OpacityMask* opacity = nullptr;
  // Participating media on either side (media/medium.h): interior fills the side opposite the front
  // normal, exterior the front side. A shape with either set and no material is an index-matched boundary.
  const Medium* interior = nullptr;
  const Medium* exterior = nullptr;
  // "camera_visible": false: camera rays pass through the shape (it still lights the scene and shows in
  // reflections); EmbreeScene::intersect_camera.
  bool camera_visible = true;
  bool has_medium_interface() const { return interior || exterior; }
  // Area lights of this shape: empty, one for the whole shape, or one per primitive.
  std::vector<const Light*> lights;
  const Light* light(uint32_t prim) const {
    if (lights.empty()) return nullptr;
    return lights.size() == 1 ? lights[0] : lights[prim];
  }
  std::string name;  // "shapes[3]" style label for messages and statistics
};

// Indexed triangles with optional per-vertex normals, uvs and tangents. Front side is counter-clockwise
// (right-handed): n = (v1 - v0) x (v2 - v0).
//
// Tangents (for normal maps, Shape::tangent): the mesh's own (xyz + handedness w, e.g. from a glTF file's
// TANGENT attribute) when it has them; else, for a mesh with per-vertex normals and texture coordinates,
// per-vertex tangents computed the MikkTSpace way (geometry/mesh_tangents.h) by prepare_tangents(); else (flat
// meshes, quads, polygons) each triangle's own dp/du, the analytic tangent of its (u, v) mapping.
class TriangleMesh final : public Shape {
 public:
  // positions.size() is the vertex count; the mesh pads the buffer itself for Embree.
  TriangleMesh(std::vector<Vec3> positions, std::vector<uint32_t> indices, std::vector<Vec3> normals = {},
               std::vector<Vec2> uvs = {}, std::vector<Vec4> tangents = {});

  unsigned attach(RTCDevice device, RTCScene scene) const override;
  void interaction(const Ray& ray, float t, uint32_t prim, float u, float v, const Vec3& ng,
                   SurfaceInteraction& si) const override;
  size_t primitive_count() const override { return indices_.size() / 3; }
  float primitive_area(uint32_t prim) const override;
  void bounds(Vec3& lo, Vec3& hi) const override;
  void uv_derivatives(const SurfaceInteraction& si, Vec3* dpdu, Vec3* dpdv) const override;
  Vec4 tangent(const SurfaceInteraction& si) const override;
  // From the vertex normals: the mean over the triangle's edges of (n_i − n_j)·(p_i − p_j) / |p_i − p_j|²
  // (Akenine-Möller et al. 2021); 0 without vertex normals (flat triangles).
  float curvature(const SurfaceInteraction& si) const override;
  Vec2 hit_uv(const Ray& ray, float t, uint32_t prim, float u, float v) const override;
  void prepare_tangents() override;
  void set_pose(const Mat4& pose) override;
  void refresh(RTCGeometry geom) const override;
  size_t open_edges() const override;

  size_t vertex_count() const { return vertex_count_; }
  const Vec3& position(uint32_t i) const { return positions_[i]; }
  Vec3 triangle_vertex(uint32_t prim, int k) const { return positions_[indices_[3 * prim + k]]; }
  // The (u, v) of a triangle's corner ((0, 0) for a mesh without texture coordinates).
  Vec2 triangle_uv(uint32_t prim, int k) const { return uvs_.empty() ? Vec2(0.0f) : uvs_[indices_[3 * prim + k]]; }
  bool has_normals() const { return !normals_.empty(); }
  bool has_tangents() const { return !tangents_.empty(); }
  // An OBJ file's usemtl groups (io/mesh_io.h MeshData::groups), kept when the scene maps them to its materials
  // by name: one group index per triangle into `names`.
  void set_groups(std::vector<uint32_t> groups, std::vector<std::string> names);
  const std::vector<std::string>& group_names() const { return group_names_; }
  // One mesh per group that has triangles, with that group's index, each holding only the vertices it uses.
  std::vector<std::pair<uint32_t, std::unique_ptr<TriangleMesh>>> split_by_group() const;

 private:
  size_t vertex_count_;
  std::vector<Vec3> positions_;  // vertex_count_ + 1 entries: Embree reads 16 bytes per vertex
  std::vector<uint32_t> indices_;
  std::vector<Vec3> normals_;
  std::vector<Vec2> uvs_;
  std::vector<Vec4> tangents_;    // empty or vertex_count_ entries
  std::vector<uint32_t> groups_;  // empty or one per triangle
  std::vector<std::string> group_names_;
  struct Rest;  // the geometry as loaded, for set_pose
  std::shared_ptr<const Rest> rest_;
};

// Analytic sphere, intersected by Embree's sphere primitive. Outside is the front side.
class Sphere final : public Shape {
 public:
  Sphere(const Vec3& center, float radius) : center_(center), radius_(radius) {}

  unsigned attach(RTCDevice device, RTCScene scene) const override;
  void interaction(const Ray& ray, float t, uint32_t prim, float u, float v, const Vec3& ng,
                   SurfaceInteraction& si) const override;
  size_t primitive_count() const override { return 1; }
  float primitive_area(uint32_t) const override { return 4.0f * kPi * radius_ * radius_; }
  // Uniform point on the surface, pdf per unit area.
  AreaSample sample_surface(const Vec2& u) const;
  void bounds(Vec3& lo, Vec3& hi) const override;
  void uv_derivatives(const SurfaceInteraction& si, Vec3* dpdu, Vec3* dpdv) const override;
  // dp/du normalized: (−sin φ, 0, cos φ) seen from the centre; w = −1, since u runs clockwise seen from outside
  // (from +x towards +z about +y), so dp/dv = w · cross(n, dp/du) direction-wise.
  Vec4 tangent(const SurfaceInteraction& si) const override;
  float curvature(const SurfaceInteraction&) const override { return 1.0f / radius_; }
  Vec2 hit_uv(const Ray& ray, float t, uint32_t prim, float u, float v) const override;
  // A pose that scales unevenly would make an ellipsoid: refused by the loader, here scaled by the mean.
  void set_pose(const Mat4& pose) override;
  void refresh(RTCGeometry geom) const override;
  size_t open_edges() const override { return 0; }

  const Vec3& center() const { return center_; }
  float radius() const { return radius_; }
  // Bound on the distance between a computed hit point (Embree's float intersection, reprojected onto the
  // sphere) and the true surface: a few float ulps of the largest magnitude involved, |center| + radius. Rays
  // leave that far from the surface (SurfaceInteraction::p_error), so that even a ground sphere of radius 10^4
  // never re-hits itself.
  float position_error() const { return kPositionError * (max_component(glm::abs(center_)) + radius_); }
  static constexpr float kPositionError = 32.0f * 0x1p-24f;

 private:
  Vec3 center_;
  float radius_;
  std::optional<std::pair<Vec3, float>> rest_;  // centre and radius as loaded, for set_pose
};

// The hit's dp/du and dp/dv, tangent frame and curvature (Shape::uv_derivatives, tangent, curvature) in world
// space, for a hit on a shape of the scene or inside an instance (si.instance). Every reader of a hit uses these.
void surface_uv_derivatives(const SurfaceInteraction& si, Vec3* dpdu, Vec3* dpdv);
Vec4 surface_tangent(const SurfaceInteraction& si);
float surface_curvature(const SurfaceInteraction& si);

// The texture-space footprint of si's ray cone (si.cone_width): the ellipse the cone cuts from the tangent plane,
// its axes w / |cos theta| along the ray's projection and w across it, mapped to (u, v) by least squares through
// dp/du and dp/dv. Zero when si has no cone or its (u, v) is degenerate.
void uv_footprint(const SurfaceInteraction& si, Vec2* duvdx, Vec2* duvdy);

}  // namespace kozu
