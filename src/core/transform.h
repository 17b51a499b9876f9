// Affine transforms of points, vectors and normals (column-vector convention, glm layout).
#pragma once

#include "core/math.h"

#include <glm/gtc/matrix_transform.hpp>

namespace kozu {

class Transform {
 public:
  Transform() = default;
  explicit Transform(const Mat4& m) : m_(m), normal_(glm::transpose(glm::inverse(Mat3(m)))) {}

  static Transform translate(const Vec3& t) { return Transform(glm::translate(Mat4(1.0f), t)); }
  static Transform scale(const Vec3& s) { return Transform(glm::scale(Mat4(1.0f), s)); }
  // Rotation by `degrees` about `axis` (right-handed).
  static Transform rotate(const Vec3& axis, float degrees) {
    return Transform(glm::rotate(Mat4(1.0f), glm::radians(degrees), glm::normalize(axis)));
  }

  Transform operator*(const Transform& o) const { return Transform(m_ * o.m_); }

  Vec3 point(const Vec3& p) const { return Vec3(m_ * Vec4(p, 1.0f)); }
  Vec3 vector(const Vec3& v) const { return Mat3(m_) * v; }
  Vec3 normal(const Vec3& n) const { return normal_ * n; }
  const Mat4& matrix() const { return m_; }
  float determinant() const { return glm::determinant(Mat3(m_)); }

 private:
  Mat4 m_{1.0f};
  Mat3 normal_{1.0f};
};

}  // namespace kozu
