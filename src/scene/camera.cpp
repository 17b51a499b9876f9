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

namespace {

// Row-vector matrices (OpenEXR's and Imath's layout): m[r][c], p' = p m.
using M4 = std::array<std::array<double, 4>, 4>;
M4 multiply(const M4& a, const M4& b) {
  M4 m{};
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c)
      for (int k = 0; k < 4; ++k) m[r][c] += a[r][k] * b[k][c];
  return m;
}
Camera::Matrix44 to_float(const M4& m) {
  Camera::Matrix44 out;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out[4 * r + c] = static_cast<float>(m[r][c]);
  return out;
}

// World to OpenEXR camera space: the columns are the camera's right, up and forward axes (x right, y up, z the view
// direction: a left-handed frame in kozu's right-handed world), the last row moves the camera to the origin.
M4 world_to_camera_rows(const Vec3& position, const Vec3& right, const Vec3& up, const Vec3& forward) {
  M4 m{};
  const Vec3 axes[3] = {right, up, forward};
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) m[r][c] = axes[c][r];
    m[3][c] = -(double(axes[c].x) * position.x + double(axes[c].y) * position.y + double(axes[c].z) * position.z);
  }
  m[3][3] = 1.0;
  return m;
}

}  // namespace

Camera::Matrix44 Camera::exr_world_to_camera() const {
  return to_float(world_to_camera_rows(position_, right_, up_, forward_));
}

std::optional<Camera::Matrix44> Camera::exr_world_to_ndc() const {
  if (projection_ == Projection::Panorama) return std::nullopt;
  const double aspect = static_cast<double>(resolution_.x) / resolution_.y;
  // Camera space to NDC, inverting generate_ray: film x / width and y / height.
  M4 p{};
  if (projection_ == Projection::Orthographic) {
    // x_ndc = 1/2 + x / (scale aspect), y_ndc = 1/2 - y / scale (an affine map, w = 1).
    p[0][0] = 1.0 / (double(scale_) * aspect);
    p[1][1] = -1.0 / double(scale_);
    p[2][2] = 1.0;
    p[3][0] = 0.5;
    p[3][1] = 0.5;
    p[3][3] = 1.0;
  } else {
    // x_ndc = 1/2 + x / (2 z tan(fov/2) aspect), y_ndc = 1/2 - y / (2 z tan(fov/2)), after division by w = z; the
    // thin lens images its plane of focus the same way. z_ndc = 1 - n / z with n = 0.001 keeps the matrix
    // invertible (OpenEXR discards it).
    const double t = std::tan(glm::radians(double(fov_)) * 0.5);
    p[0][0] = 0.5 / (t * aspect);
    p[1][1] = -0.5 / t;
    p[2][0] = 0.5;
    p[2][1] = 0.5;
    p[2][2] = 1.0;
    p[2][3] = 1.0;
    p[3][2] = -1e-3;
  }
  return to_float(multiply(world_to_camera_rows(position_, right_, up_, forward_), p));
}

}  // namespace kozu
