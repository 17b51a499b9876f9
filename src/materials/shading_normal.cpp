#include "materials/shading_normal.h"

namespace kozu {

Vec3 bend_shading_normal(const Vec3& n, const Vec3& wo, const Vec3& ng) {
  const float cos_geo = glm::dot(wo, ng);
  const Vec3 v = cos_geo >= 0.0f ? wo : -wo;  // wo on ng's side
  const float c = std::min(kMinShadingCos, std::abs(cos_geo));
  Vec3 bent = n;
  const float cos_n = glm::dot(v, n);
  if (cos_n < c) bent = glm::normalize(n + (c - cos_n) * v);
  if (!(glm::dot(bent, ng) > 0.0f) || !is_finite(bent)) return ng;
  return bent;
}

void set_shading_normal(SurfaceInteraction& si, const Vec3& n, const Vec3& tangent) {
  const float l = glm::length(n);
  if (!(l > 0.0f) || !std::isfinite(l)) return;
  const Vec3 nb = bend_shading_normal(n / l, si.wo, si.ng);
  const Vec3 s = tangent - glm::dot(tangent, nb) * nb;
  const float ls = glm::length(s);
  if (!(ls > 1e-6f) || !std::isfinite(ls)) {
    si.shading = Frame(nb);
    return;
  }
  const Vec3 su = s / ls;
  si.shading = Frame(su, glm::cross(nb, su), nb);
}

}  // namespace kozu
