#include "materials/opacity_mask.h"

#include <algorithm>

namespace kozu {

float TextureOpacity::opacity(const Vec2& uv) const {
  TextureQuery q;
  q.uv = uv;
  const float a = texture_->eval_float(q);
  return a > 0.0f ? std::min(a, 1.0f) : 0.0f;  // NaN: a hole
}

}  // namespace kozu
