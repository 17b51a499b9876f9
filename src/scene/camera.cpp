#include "scene/camera.h"

#include "core/warp.h"

#include <cmath>
#include <stdexcept>

namespace kozu {

Camera::Camera(const Vec3& position, const Vec3& look_at, const Vec3& up, float fov_degrees, Vec2i resolution,
               float aperture_radius, float focus_distance)
    : position_(position),
      fov_(fov_degrees),
      resolution_(resolution),
      aperture_radius_(aperture_radius),
      focus_distance_(focus_distance) {
  forward_ = glm::normalize(look_at - position);
  right_ = glm::normalize(glm::cross(forward_, up));
  up_ = glm::cross(right_, forward_);
  look_at_ = look_at;
  world_up_ = up;
  update();
}

Camera Camera::with_projection(Projection projection, const Vec3& position, const Vec3& look_at, const Vec3& up,
                               Vec2i resolution, float scale) {
  Camera c(position, look_at, up, 40.0f, resolution);
  c.projection_ = projection;
  c.scale_ = scale;
  return c;
}

Camera Camera::moved(const Vec3& position, const Vec3& look_at, float fov_degrees) const {
  if (!(glm::length(look_at - position) > 0.0f)) throw std::invalid_argument("look_at equals position");
  if (glm::length(glm::cross(glm::normalize(look_at - position), glm::normalize(world_up_))) < 1e-4f)
    throw std::invalid_argument("the view direction is parallel to the camera's up vector");
  Camera c(position, look_at, world_up_, fov_degrees, resolution_, aperture_radius_, focus_distance_);
  c.projection_ = projection_;
  c.scale_ = scale_;
  return c;
}

RayCone Camera::pixel_cone() const {
  const float h = static_cast<float>(resolution_.y);
  switch (projection_) {
    case Projection::Orthographic:
      return {scale_ / h, 0.0f};
    case Projection::Panorama:
      return {0.0f, kPi / h};
    case Projection::Perspective:
      break;
  }
  return {0.0f, 2.0f * tan_half_ / h};
}

void Camera::set_resolution(Vec2i r) {
  resolution_ = r;
  update();
}

void Camera::update() {
  tan_half_ = std::tan(glm::radians(fov_) * 0.5f);
  aspect_ = static_cast<float>(resolution_.x) / static_cast<float>(resolution_.y);
}

Ray Camera::generate_ray(const Vec2& film, const Vec2& lens_u) const {
  if (projection_ == Projection::Panorama) {
    // The lat-long layout of environment images, in the camera's frame (camera.h).
    const float phi = (film.x / resolution_.x - 0.5f) * kTwoPi, theta = film.y / resolution_.y * kPi;
    const float sin_t = std::sin(theta);
    const Vec3 d = sin_t * std::sin(phi) * right_ + std::cos(theta) * up_ + sin_t * std::cos(phi) * forward_;
    return Ray{position_, glm::normalize(d), kInfinity};
  }
  if (projection_ == Projection::Orthographic) {
    const float sx = (film.x / resolution_.x - 0.5f) * scale_ * aspect_;
    const float sy = (0.5f - film.y / resolution_.y) * scale_;
    return Ray{position_ + sx * right_ + sy * up_, forward_, kInfinity};
  }
  // Normalised device coordinates in [-1, 1], y up.
  const float sx = (2.0f * film.x / resolution_.x - 1.0f) * tan_half_ * aspect_;
  const float sy = (1.0f - 2.0f * film.y / resolution_.y) * tan_half_;
  Vec3 d = forward_ + sx * right_ + sy * up_;
  if (aperture_radius_ <= 0.0f) return Ray{position_, glm::normalize(d), kInfinity};
  // Thin lens: all rays through the film point meet on the plane at focus_distance.
  const Vec3 focus = position_ + d * focus_distance_;  // d has unit forward component
  const Vec2 lens = aperture_radius_ * warp::square_to_disk_concentric(lens_u);
  const Vec3 o = position_ + lens.x * right_ + lens.y * up_;
  return Ray{o, glm::normalize(focus - o), kInfinity};
}

}  // namespace kozu
