// MediumTransform: places a voxel medium's grid in the scene. The grid lives in its local space (the box its
// file gives); the medium's "transform" (docs/scene-format.md, the same object as a mesh's) maps local space to
// the scene. Coefficients stay per scene unit, as in pbrt-v4's grid media: the transform moves, turns and
// stretches where the field is, not how dense it is, so σt(p, ω) = σt_local(M⁻¹p, ω_local).
//
// Rays keep their scene parameter t: a majorant walk in local space uses o' = M⁻¹o and the (non-unit)
// d' = M⁻¹d, whose points o' + t d' are the images of o + t d, so the majorant cells' values (per scene unit)
// bound the extinction at the same t.
//
// Directions. Density-only media ignore them. SGGX media (Heitz et al. 2015) need the flakes turned with the grid: for
// a similarity M = s R (R orthogonal, s > 0), S_world = R S Rᵀ, and σ(ω) = sqrt(ωᵀ R S Rᵀ ω) is the local
// σ at Rᵀω. Any other linear part would also reshape the flakes (a non-uniform stretch changes their
// projected areas), so SGGX media accept similarities only (is_similarity).
#pragma once

#include "core/math.h"
#include "core/transform.h"

#include <cmath>

namespace kozu {

class MediumTransform {
 public:
  MediumTransform() = default;  // identity
  explicit MediumTransform(const Transform& world_from_local)
      : identity_(world_from_local.matrix() == Mat4(1.0f)),
        local_from_world_(glm::inverse(world_from_local.matrix())),
        linear_(Mat3(world_from_local.matrix())) {
    const float s2 = glm::dot(linear_[0], linear_[0]);
    scale_ = std::sqrt(s2);
    rotation_ = linear_ / scale_;
  }

  bool identity() const { return identity_; }
  // The local point of a scene point.
  Vec3 point(const Vec3& p) const { return identity_ ? p : Vec3(local_from_world_ * Vec4(p, 1.0f)); }
  // The local image of a scene vector (not normalized: it carries the scene parameter t, header comment).
  Vec3 vector(const Vec3& d) const { return identity_ ? d : Mat3(local_from_world_) * d; }
  // For similarities: the local unit direction Rᵀω of a scene unit direction ω, and R S Rᵀ.
  Vec3 direction(const Vec3& w) const { return identity_ ? w : glm::transpose(rotation_) * w; }
  const Mat3& rotation() const { return rotation_; }
  // For similarities: s, the scene length of a local unit length.
  float scale() const { return scale_; }

  // Whether the linear part is s·R with R orthogonal (columns orthogonal and of equal length), within a
  // relative 1e-4.
  bool is_similarity() const {
    const float s2 = scale_ * scale_;
    for (int a = 0; a < 3; ++a)
      for (int b = a; b < 3; ++b) {
        const float expected = a == b ? s2 : 0.0f;
        if (std::abs(glm::dot(linear_[a], linear_[b]) - expected) > 1e-4f * s2) return false;
      }
    return true;
  }

 private:
  bool identity_ = true;
  Mat4 local_from_world_{1.0f};
  Mat3 linear_{1.0f};
  Mat3 rotation_{1.0f};
  float scale_ = 1.0f;
};

}  // namespace kozu
