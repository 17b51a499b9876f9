// Embree scene over kozu shapes: closest-hit and any-hit queries, one ray at a time. Shapes with an opacity
// cut-out (Shape::opacity) get an intersection and occlusion filter that drops the hits in their holes.
#pragma once

#include "geometry/instance.h"
#include "geometry/shape.h"

#include <embree3/rtcore.h>

#include <memory>
#include <string>
#include <vector>

namespace kozu {

// Records the rays a render traces, so benchmarks can replay exactly those rays through Embree
// alone. Not thread-safe: attach only for single-threaded recording.
struct RayLog {
  std::vector<Ray> closest;
  std::vector<Ray> shadow;
  size_t limit = 0;  // stop recording after this many rays of each kind (0 = no limit)
};

// Memory checks before the accelerator is built (the limit of core/memory.h), with costs measured by peak resident
// memory (embree_scene.cpp). Throws InputError(file, json_path, "the scene's N instances need about X but only Y
// of the Z limit (SOURCE) is left") when `instances` instances (kozu's objects and their share of Embree's
// hierarchy) do not fit in what is left; called before the scene's instances are created.
void check_instance_memory(size_t instances, const std::string& file, const std::string& json_path);

class EmbreeScene {
 public:
  // The shapes must outlive this object. Builds with Embree's high-quality (SAH + spatial split)
  // builder: kozu scenes are traced far longer than they take to build. First checks that the hierarchy's
  // estimated memory (its primitives, each instanced object once, and its instances) fits in what is left of the
  // memory limit, and throws std::runtime_error with a message saying so when it does not.
  explicit EmbreeScene(const std::vector<std::unique_ptr<Shape>>& shapes);
  ~EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  // Closest hit along ray in (0, ray.tmax); fills si and returns true on a hit.
  bool intersect(const Ray& ray, SurfaceInteraction& si) const;
  // As intersect, for a camera ray: shapes with camera_visible false are stepped over (a light that lights the
  // scene without being seen, as Cycles' lights are by default).
  bool intersect_camera(const Ray& ray, SurfaceInteraction& si) const;
  // Whether a camera ray meets a shape it sees (the coverage of --alpha).
  bool camera_hits(const Ray& ray) const {
    SurfaceInteraction si;
    return hidden_from_camera_ ? intersect_camera(ray, si) : occluded(ray);
  }
  // True if anything blocks the open segment (0, ray.tmax).
  bool occluded(const Ray& ray) const;
  // Every hit with `shape` along (0, ray.tmax), nearest first, up to max_hits; hits with other shapes
  // are stepped over. Returns the count; *rays grows by the number of Embree queries. (BSSRDF probe rays.)
  // A shape inside an instance is matched with its instance (null for the scene's own shapes).
  int intersect_shape(const Ray& ray, const Shape* shape, const Instance* instance, SurfaceInteraction* hits,
                      int max_hits, uint64_t* rays) const;

  // Hands shapes moved by Shape::set_pose to Embree and rebuilds the hierarchy (animation frames).
  void update(const std::vector<const Shape*>& moved);
  RTCScene handle() const { return scene_; }
  void set_ray_log(RayLog* log) { log_ = log; }
  const Shape* shape(unsigned geom_id) const { return by_geom_id_[geom_id]; }

 private:
  // Closest hit beyond tnear; returns its geometry id (RTC_INVALID_GEOMETRY_ID on a miss).
  unsigned intersect_from(const Ray& ray, float tnear, SurfaceInteraction& si) const;

  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  std::vector<const Shape*> by_geom_id_;
  std::vector<const Instance*> instances_;  // by geometry id; null for shapes that are not instances
  RayLog* log_ = nullptr;
  bool hidden_from_camera_ = false;  // a shape has camera_visible false
};

// Embree reports errors through a callback; kozu turns them into exceptions at the call site.
RTCDevice make_embree_device();
// Adds `shape` to `scene` (with its opacity filter, if it has a cut-out) and returns its geometry id; throws on an
// Embree error. The scene is committed by the caller.
unsigned attach_shape(RTCDevice device, RTCScene scene, const Shape& shape);

}  // namespace kozu
