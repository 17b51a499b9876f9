#include "materials/normal_map.h"

#include "geometry/shape.h"
#include "materials/shading_normal.h"

namespace kozu {

Vec3 NormalMap::decode(const Rgb& texel) const {
  Vec3 m = 2.0f * Vec3(texel.r, texel.g, texel.b) - 1.0f;
  if (flip_y_) m.y = -m.y;
  return m;
}

Vec3 NormalMap::perturbed_normal(const Rgb& texel, const Vec3& t, float w, const Vec3& n) const {
  const Vec3 m = decode(texel);
  const Vec3 b = w * glm::cross(n, t);
  return strength_ * (m.x * t + m.y * b) + m.z * n;
}

Vec3 NormalMap::blended_tangent_normal(const Rgb& texel, const Rgb& detail_texel) const {
  Vec3 base = decode(texel);
  base.x *= strength_;
  base.y *= strength_;
  return blend_detail_normal(blend_, base, decode(detail_texel));
}

Vec3 NormalMap::perturbed_normal(const Rgb& texel, const Rgb& detail_texel, const Vec3& t, float w,
                                 const Vec3& n) const {
  const Vec3 m = blended_tangent_normal(texel, detail_texel);
  const Vec3 b = w * glm::cross(n, t);
  return m.x * t + m.y * b + m.z * n;
}

void NormalMap::apply(SurfaceInteraction& si) const {
  TextureQuery q;
  q.uv = si.uv;
  uv_footprint(si, &q.duvdx, &q.duvdy);
  q.fine = si.fine_filtering;
  const Vec4 tw = surface_tangent(si);
  Vec3 t(tw);
  float w = tw.w;
  if (w == 0.0f) {  // no (u, v) parametrization here: any tangent, so that at least the map's tilt is kept
    t = si.shading.s;
    w = 1.0f;
  }
  // The detail map reads the same (u, v) and footprint; its own uv_scale / uv_offset apply inside the texture.
  const Vec3 n = detail_ ? perturbed_normal(texture_->eval(q), detail_->eval(q), t, w, si.shading.n)
                         : perturbed_normal(texture_->eval(q), t, w, si.shading.n);
  set_shading_normal(si, n, t);
}

}  // namespace kozu
