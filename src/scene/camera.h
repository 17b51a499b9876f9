// The camera: perspective (optionally a thin lens, for depth of field), orthographic, or a lat-long panorama.
//
// Parameters (scene "camera" block)
//   type             string  "perspective"   "perspective" | "thinlens" | "orthographic" | "panorama"
//   position         vec3    required
//   look_at          vec3    required
//   up               vec3    [0, 1, 0]
//   fov              float   40              vertical field of view, degrees, in (0, 180)
//   resolution       [w, h]  [1280, 720]
//   aperture_radius  float   0 (thinlens: required, > 0)   lens radius, scene units
//   focus_distance   float   |look_at - position|          distance to the plane in focus
//   scale            float   required (orthographic)       the image's height in scene units
//
// orthographic: parallel rays along the view direction from a film of height `scale` centred on position.
// panorama: the whole sphere of directions in the lat-long layout of environment images (lights/environment.h),
// in the camera's frame: u = 1/2 + atan2(right, forward) / 2 pi, v = acos(up) / pi, so the image centre looks
// along the view direction and the top row at the camera's up; a camera looking down -z with up +y renders an
// environment image as stored.
#pragma once

#include "core/math.h"
#include "geometry/ray.h"
#include "geometry/ray_cone.h"

#include <array>
#include <optional>

namespace kozu {

class Camera {
 public:
  enum class Projection { Perspective, Orthographic, Panorama };

  Camera() = default;
  Camera(const Vec3& position, const Vec3& look_at, const Vec3& up, float fov_degrees, Vec2i resolution,
         float aperture_radius = 0.0f, float focus_distance = 1.0f);
  // An orthographic camera (film height `scale`) or a panorama (scale unused) looking from position to look_at.
  static Camera with_projection(Projection projection, const Vec3& position, const Vec3& look_at, const Vec3& up,
                                Vec2i resolution, float scale = 1.0f);

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
  Projection projection() const { return projection_; }
  // A camera ray's cone (its footprint on the scene, for texture filtering and the volumes' level of detail): the
  // angle one pixel subtends at the image centre (perspective: its height over the unit-distance film; panorama:
  // pi / height), or the pixel's width (orthographic).
  RayCone pixel_cone() const;

  // OpenEXR's standard camera attributes (ImfStandardAttributes.h): 4x4 matrices for row vectors (p' = p M, with
  // the translation in the last row, Imath's M44f), row-major. Camera space is OpenEXR's (and RenderMan's): left-
  // handed, origin at the camera, +x right and +y up in the image, +z the viewing direction. NDC: (0, 0) the
  // display window's upper-left corner, (1, 1) its lower-right, reached by p M then division by w; NDC z, which
  // OpenEXR discards, is 1 - 0.001 / z_camera for perspective (z_camera for orthographic). A panorama has no NDC
  // matrix (no projective map covers a sphere of directions): nullopt.
  using Matrix44 = std::array<float, 16>;
  Matrix44 exr_world_to_camera() const;
  std::optional<Matrix44> exr_world_to_ndc() const;

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
  Projection projection_ = Projection::Perspective;
  float scale_ = 1.0f;  // orthographic: the film's height
};

}  // namespace kozu
