// Affine transforms of points, vectors and normals (column-vector convention, glm layout).
#pragma once

#include "core/math.h"

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>

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
  // True when the linear part is a rotation (or a mirror) times a uniform scale: it keeps angles and maps a sphere
  // to a sphere. *scale receives the scale factor.
  bool is_similarity(float* scale = nullptr) const {
    const Vec3 c[3] = {Vec3(m_[0]), Vec3(m_[1]), Vec3(m_[2])};
    const float s2 = (glm::dot(c[0], c[0]) + glm::dot(c[1], c[1]) + glm::dot(c[2], c[2])) / 3.0f;
    if (scale) *scale = std::sqrt(s2);
    for (int a = 0; a < 3; ++a)
      for (int b = a; b < 3; ++b)
        if (std::abs(glm::dot(c[a], c[b]) - (a == b ? s2 : 0.0f)) > 1e-4f * s2) return false;
    return true;
  }

 private:
  Mat4 m_{1.0f};
  Mat3 normal_{1.0f};
};

}  // namespace kozu
