#include "scene/camera.h"

#include "core/warp.h"

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

Camera Camera::moved(const Vec3& position, const Vec3& look_at, float fov_degrees) const {
  if (!(glm::length(look_at - position) > 0.0f)) throw std::invalid_argument("look_at equals position");
  if (glm::length(glm::cross(glm::normalize(look_at - position), glm::normalize(world_up_))) < 1e-4f)
    throw std::invalid_argument("the view direction is parallel to the camera's up vector");
  return Camera(position, look_at, world_up_, fov_degrees, resolution_, aperture_radius_, focus_distance_);
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
