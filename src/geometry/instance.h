// instance: a named group of shapes ("objects" in the scene), stored once, placed any number of times by an affine
// transform through Embree's instance geometry (RTC_GEOMETRY_TYPE_INSTANCE): a forest of 10^5 trees keeps one
// tree's triangles and hierarchy, plus a top-level hierarchy over the instances and a few hundred bytes each.
//
// A hit inside an instance is computed by the object's own shape in object space (the ray taken there by the
// inverse transform, with its unnormalised direction, so t is the world t) and carried to world space: points and
// tangent vectors by M, normals by M^-T, the position error bound by M's norm plus the transform's own rounding.
// SurfaceInteraction::instance names the instance, so the queries that read the hit's shape again (texture
// footprints, tangents for normal maps, curvature for ray cones, probe rays for subsurface scattering) go through
// surface_uv_derivatives / surface_tangent / surface_curvature and EmbreeScene::intersect_shape, which take it
// into account. Non-uniform scales are allowed (a sphere becomes an ellipsoid); a mirroring transform keeps the
// object's front side.
//
// Parameters (scene: "objects": {"NAME": [shapes…]}, and a shape {"type": "instance", ...})
//   object     string     required  the object's name
//   transform  transform  identity  object to world
//   name       string     —         as for any shape (animation tracks move an instance)
// An object's shapes cannot emit light (area lights sample each surface once, in world space) and cannot be
// glTF files or instances themselves.
#pragma once

#include "core/transform.h"
#include "geometry/shape.h"

#include <memory>
#include <vector>

namespace kozu {

// The shapes of one object and, once attached, their Embree scene (built once per device, shared by every
// instance).
class InstancedObject {
 public:
  explicit InstancedObject(std::vector<std::unique_ptr<Shape>> shapes);
  ~InstancedObject();
  InstancedObject(const InstancedObject&) = delete;
  InstancedObject& operator=(const InstancedObject&) = delete;

  // The object's committed Embree scene on `device` (built on the first call).
  RTCScene embree_scene(RTCDevice device) const;
  const Shape* shape(unsigned geom_id) const { return by_geom_id_[geom_id]; }
  const std::vector<std::unique_ptr<Shape>>& shapes() const { return shapes_; }
  // Object-space bounds of every shape (computed once: instances ask for them each).
  void bounds(Vec3& lo, Vec3& hi) const {
    lo = glm::min(lo, lo_);
    hi = glm::max(hi, hi_);
  }

 private:
  std::vector<std::unique_ptr<Shape>> shapes_;
  Vec3 lo_{kInfinity}, hi_{-kInfinity};
  mutable RTCDevice device_ = nullptr;
  mutable RTCScene scene_ = nullptr;
  mutable std::vector<const Shape*> by_geom_id_;
};

class Instance final : public Shape {
 public:
  Instance(std::shared_ptr<const InstancedObject> object, const Mat4& object_to_world);

  unsigned attach(RTCDevice device, RTCScene scene) const override;
  // The hit of the object's geometry `geom_id` (Embree's hit.geomID under hit.instID) in world space; ng is
  // Embree's object-space geometric normal.
  void instanced_interaction(const Ray& ray, float t, unsigned geom_id, uint32_t prim, float u, float v, const Vec3& ng,
                             SurfaceInteraction& si) const;

  // The queries on a hit of one of the object's shapes (si.instance == this), in world space.
  void uv_derivatives_of(const SurfaceInteraction& si, Vec3* dpdu, Vec3* dpdv) const;
  Vec4 tangent_of(const SurfaceInteraction& si) const;
  float curvature_of(const SurfaceInteraction& si) const;

  // Shape's interface: hits carry the object's shape (si.shape) and this instance (si.instance), so the
  // per-hit queries below are never asked of the instance itself; they answer for an empty surface.
  void interaction(const Ray& ray, float t, uint32_t prim, float u, float v, const Vec3& ng,
                   SurfaceInteraction& si) const override;
  size_t primitive_count() const override { return 0; }
  float primitive_area(uint32_t) const override { return 0.0f; }
  void bounds(Vec3& lo, Vec3& hi) const override;
  void uv_derivatives(const SurfaceInteraction&, Vec3* dpdu, Vec3* dpdv) const override { *dpdu = *dpdv = Vec3(0); }
  Vec4 tangent(const SurfaceInteraction&) const override { return Vec4(0.0f); }
  float curvature(const SurfaceInteraction&) const override { return 0.0f; }
  Vec2 hit_uv(const Ray&, float, uint32_t, float, float) const override { return Vec2(0.0f); }
  // Animation: the instance placed by pose after its own transform (as a mesh's vertices are).
  void set_pose(const Mat4& pose) override;
  void refresh(RTCGeometry geom) const override;
  size_t open_edges() const override { return 0; }

  const InstancedObject& object() const { return *object_; }
  const Mat4& object_to_world() const { return to_world_; }

 private:
  void set_transform(const Mat4& m);
  // A copy of the world-space hit si in object space, for the object's shape to answer queries on.
  SurfaceInteraction to_object_space(const SurfaceInteraction& si) const;

  std::shared_ptr<const InstancedObject> object_;
  Mat4 rest_;                  // the transform as loaded (set_pose composes with it)
  Mat4 to_world_, to_object_;  // object to world and back
  Mat3 normal_to_world_;       // M^-T
  float norm_ = 1.0f;          // the largest column length of M (how far errors grow)
  float det_sign_ = 1.0f;      // -1 for a mirroring transform
};

}  // namespace kozu
