// The texture interface: a value at a surface point, filtered over the point's footprint in texture space.
//
// A lookup gives the point's (u, v) and how (u, v) changes from one pixel to the next along the image's x and y
// (the footprint, from ray differentials or ray cones; zero for a point lookup). Every texture returns RGB; a
// number-valued parameter reads the first channel (an image texture's "channel" key picks which of the file's
// channels that is). Textures are immutable after loading and safe to evaluate from any thread.
#pragma once

#include "core/color.h"
#include "core/math.h"

namespace kozu {

struct TextureQuery {
  Vec2 uv{0.0f};
  Vec2 duvdx{0.0f}, duvdy{0.0f};  // d(u, v)/dx and d(u, v)/dy across one pixel; zero: no filtering
  bool fine = true;                // false: an indirect hit, where an EWA image lookup becomes trilinear
};

class Texture {
 public:
  virtual ~Texture() = default;
  virtual Rgb eval(const TextureQuery& q) const = 0;
  float eval_float(const TextureQuery& q) const { return eval(q).r; }
  // True when the value is the same everywhere (materials may then precompute what depends on it).
  virtual bool is_constant() const { return false; }
};

// {"type": "constant", "value": v}, and what a plain number or [r, g, b] in a textureable key becomes.
class ConstantTexture final : public Texture {
 public:
  explicit ConstantTexture(const Rgb& value) : value_(value) {}
  Rgb eval(const TextureQuery&) const override { return value_; }
  bool is_constant() const override { return true; }

 private:
  Rgb value_;
};

}  // namespace kozu
