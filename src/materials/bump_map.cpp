#include "materials/bump_map.h"

#include "geometry/shape.h"
#include "materials/shading_normal.h"

namespace kozu {

Vec3 BumpMap::bumped_normal(const Vec3& dpdu, const Vec3& dpdv, const Vec3& n, float dhdu, float dhdv) {
  const Vec3 pu = dpdu - glm::dot(dpdu, n) * n + dhdu * n;
  const Vec3 pv = dpdv - glm::dot(dpdv, n) * n + dhdv * n;
  Vec3 m = glm::cross(pu, pv);
  const float l = glm::length(m);
  if (!(l > 0.0f) || !std::isfinite(l)) return n;
  m /= l;
  return glm::dot(m, n) < 0.0f ? -m : m;
}

void BumpMap::apply(SurfaceInteraction& si) const {
  Vec3 dpdu, dpdv;
  surface_uv_derivatives(si, &dpdu, &dpdv);
  if (glm::dot(dpdu, dpdu) == 0.0f || glm::dot(dpdv, dpdv) == 0.0f) return;  // no (u, v) parametrization here
  TextureQuery q;
  q.uv = si.uv;
  uv_footprint(si, &q.duvdx, &q.duvdy);
  q.fine = si.fine_filtering;
  float du = 0.5f * (std::abs(q.duvdx.x) + std::abs(q.duvdy.x));
  float dv = 0.5f * (std::abs(q.duvdx.y) + std::abs(q.duvdy.y));
  if (!(du > 0.0f)) du = kDefaultDelta;
  if (!(dv > 0.0f)) dv = kDefaultDelta;
  const auto height = [&](const Vec2& offset) {
    TextureQuery o = q;
    o.uv += offset;
    return height_->eval_float(o);
  };
  const float dhdu = scale_ * (height(Vec2(du, 0.0f)) - height(Vec2(-du, 0.0f))) / (2.0f * du);
  const float dhdv = scale_ * (height(Vec2(0.0f, dv)) - height(Vec2(0.0f, -dv))) / (2.0f * dv);
  set_shading_normal(si, bumped_normal(dpdu, dpdv, si.shading.n, dhdu, dhdv), dpdu);
}

}  // namespace kozu
