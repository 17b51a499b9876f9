// checker: a checkerboard of two colours, box-filtered in closed form over the lookup's footprint.
//
// Parameters
//   scale  [su, sv]  [8, 8]  checks per unit of u and v
//   a, b   rgb       0.8, 0.2  the colours; a covers the check whose lower corner is (0, 0)
//
// With x = su u and y = sv v, the board is c(x, y) = a where S(x) S(y) = 1 and b where it is −1, with the square
// wave S(x) = +1 on even cells [2k, 2k+1) and −1 on odd ones. A box filter of a separable product is the product
// of the 1D filters, so the fraction of b over the box [x0, x1] × [y0, y1] is
//   w_b = (1 − S̄x S̄y) / 2,   S̄x = (T(x1) − T(x0)) / (x1 − x0),
// with T the antiderivative of S: the triangle wave T(x) = t for t = x mod 2 in [0, 1], 2 − t in [1, 2] (the
// closed-form box filtering pbrt's checkerboard texture uses). The box's half-widths are the larger footprint
// derivative in each direction.
#pragma once

#include "textures/texture.h"

namespace kozu {

class CheckerTexture final : public Texture {
 public:
  CheckerTexture(const Vec2& scale, const Rgb& a, const Rgb& b) : scale_(scale), a_(a), b_(b) {}
  Rgb eval(const TextureQuery& q) const override;
  // The fraction of b over the box [x0, x1] × [y0, y1] in check units (exposed for tests).
  static double b_fraction(double x0, double x1, double y0, double y1);

 private:
  Vec2 scale_;
  Rgb a_, b_;
};

}  // namespace kozu
