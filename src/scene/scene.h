// Everything a render needs, after loading: camera, settings, materials, shapes, lights and the
// Embree acceleration structure. Owned objects are never moved after build().
#pragma once

#include "geometry/embree_scene.h"
#include "lights/light.h"
#include "lights/light_sampler.h"
#include "lights/light_tree.h"
#include "materials/material.h"
#include "media/medium.h"
#include "scene/animation.h"
#include "scene/camera.h"
#include "scene/filter.h"
#include "scene/render_settings.h"

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace kozu {

class Scene {
 public:
  Camera camera;
  RenderSettings settings;
  Animation animation;  // keyframed camera and shapes; frames == 0 for a still
  // The shapes an animation track moves: the shape, its track in animation.shapes, and the inverse of the shape's
  // own transform (a key's transform replaces it).
  struct AnimatedShape {
    Shape* shape = nullptr;
    size_t track = 0;
    Mat4 unplace{1.0f};
    std::vector<Light*> lights;  // its area lights, refitted to each pose
  };
  std::vector<AnimatedShape> animated_shapes;
  // Motion blur: the camera at equally spaced times across the open shutter, one chosen per camera sample by an
  // extra sampler dimension (empty: every sample uses `camera`).
  std::vector<Camera> shutter_cameras;
  // Image textures read through it; declared before the materials that hold them, so it outlives them.
  std::unique_ptr<TextureCache> textures;
  std::vector<std::unique_ptr<Material>> materials;
  std::vector<std::unique_ptr<Shape>> shapes;
  std::vector<std::unique_ptr<Light>> lights;
  std::vector<std::unique_ptr<Medium>> media;
  const Medium* camera_medium = nullptr;  // the medium the camera sits in (none: vacuum)
  // The files the scene was loaded from: the scene file and every file it references.
  std::vector<std::filesystem::path> input_files;
  // Things loading left out or changed that the user should know (kozu render prints them as "warning: …").
  std::vector<std::string> warnings;
  bool has_media() const { return !media.empty(); }
  // Tells the media where the camera is and how large a pixel is (levels of detail); call after changing
  // the camera's resolution.
  void set_media_view();
  // The media's notes from the last set_media_view (a clamped level of detail), for warnings.
  std::vector<std::string> view_warnings;
  // warnings, then view_warnings.
  std::vector<std::string> all_warnings() const {
    std::vector<std::string> all = warnings;
    all.insert(all.end(), view_warnings.begin(), view_warnings.end());
    return all;
  }

  // Builds the acceleration structure, the scene bounds and the light sampler. Call once after
  // all shapes, materials and lights are in place.
  void build();
  // Moves the animated shapes to their poses at `time` (seconds) and updates what depends on them: the hierarchy,
  // the scene's bounds and the infinite lights' power. Nothing to do for a scene whose shapes stand still.
  void pose_shapes(double time);

  bool intersect(const Ray& ray, SurfaceInteraction& si) const { return accel_->intersect(ray, si); }
  bool intersect_camera(const Ray& ray, SurfaceInteraction& si) const { return accel_->intersect_camera(ray, si); }
  bool camera_hits(const Ray& ray) const { return accel_->camera_hits(ray); }
  bool occluded(const Ray& ray) const { return accel_->occluded(ray); }

  const std::vector<const Light*>& infinite_lights() const { return infinite_lights_; }
  // Every light by power ("light_selection": "power"); the light hierarchy; the lights with an aim point by power
  // (equiangular sampling in media: media/equiangular.h).
  const LightSampler& light_sampler() const { return light_sampler_; }
  const LightTree& light_tree() const { return light_tree_; }
  const LightSampler& aim_sampler() const { return aim_sampler_; }
  const EmbreeScene& accel() const { return *accel_; }
  // Benchmarks only: records every traced ray (see RayLog).
  void set_ray_log(RayLog* log) { accel_->set_ray_log(log); }
  Vec3 center() const { return center_; }
  float radius() const { return radius_; }
  size_t triangle_count() const;

 private:
  void set_bounds_and_lights(bool all_lights);
  std::unique_ptr<EmbreeScene> accel_;
  std::vector<const Light*> infinite_lights_;
  LightSampler light_sampler_;
  LightTree light_tree_;
  LightSampler aim_sampler_;
  Vec3 center_{0.0f};
  float radius_ = 1.0f;
};

}  // namespace kozu
