// Whether a direction pair is a reflection or a transmission, asked of the shading frame and of the geometric
// normal: the integrator's guard against light leaking through an opaque surface whose shading normal is bent
// (materials/shading_normal.h).
#pragma once

#include "core/math.h"

namespace kozu {

// True if the shading frame and the geometric normal agree on whether (wo, wi) is a reflection.
// cos_o_geo = dot(wo, ng), computed once per vertex.
inline bool sides_agree(float cos_o_geo, const Vec3& ng, const Vec3& wi, const Vec3& wo_local, const Vec3& wi_local) {
  const bool geometric_reflection = cos_o_geo * glm::dot(wi, ng) > 0.0f;
  const bool shading_reflection = wo_local.z * wi_local.z > 0.0f;
  return geometric_reflection == shading_reflection;
}

}  // namespace kozu
