// Perspective camera with an optional thin lens (depth of field).
//
// Parameters (scene "camera" block)
//   type             string  "perspective"   "perspective" | "thinlens"
//   position         vec3    required
//   look_at          vec3    required
//   up               vec3    [0, 1, 0]
//   fov              float   40              vertical field of view, degrees, in (0, 180)
//   resolution       [w, h]  [1280, 720]
//   aperture_radius  float   0 (thinlens: required, > 0)   lens radius, scene units
//   focus_distance   float   |look_at - position|          distance to the plane in focus
#pragma once

#include "core/math.h"
#include "geometry/ray.h"

namespace kozu {

class Camera {
 public:
  Camera() = default;
  Camera(const Vec3& position, const Vec3& look_at, const Vec3& up, float fov_degrees, Vec2i resolution,
         float aperture_radius = 0.0f, float focus_distance = 1.0f);

  // Ray through the continuous film position (pixels, origin top-left, x right, y down).
  // lens_u is only used with a nonzero aperture.
  Ray generate_ray(const Vec2& film, const Vec2& lens_u) const;

  Vec2i resolution() const { return resolution_; }
  void set_resolution(Vec2i r);
  const Vec3& position() const { return position_; }
  const Vec3& forward() const { return forward_; }  // the viewing direction (camera-space -z)
  const Vec3& look_at() const { return look_at_; }
  float fov() const { return fov_; }
  // The same camera (up vector, resolution, lens) moved: an animation's frame. Throws std::invalid_argument when
  // look_at is position or the view is parallel to the up vector.
  Camera moved(const Vec3& position, const Vec3& look_at, float fov_degrees) const;
  float tan_half_fov() const { return tan_half_; }
  // The angle one pixel subtends at the image centre (small-angle: its height over the unit-distance film), the
  // spread of camera ray cones.
  float pixel_angle() const { return 2.0f * tan_half_ / static_cast<float>(resolution_.y); }

 private:
  void update();

  Vec3 position_{0.0f}, forward_{0, 0, -1}, right_{1, 0, 0}, up_{0, 1, 0};
  Vec3 look_at_{0, 0, -1}, world_up_{0, 1, 0};
  float fov_ = 40.0f;
  Vec2i resolution_{1280, 720};
  float aperture_radius_ = 0.0f;
  float focus_distance_ = 1.0f;
  float tan_half_ = 0.0f;
  float aspect_ = 1.0f;
};

}  // namespace kozu
