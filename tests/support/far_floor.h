// The far-floor measure of the normal and gloss filtering tests (docs/wwii.md): a floor seen out to the horizon
// in the image's lower half; its far part is the 8 rows just below the horizon, cut into 8 x 8-pixel blocks whose
// means are compared with a reference's.
#pragma once

#include "render/film.h"

#include <cmath>
#include <vector>

namespace kozu::test {

// Means (green channel) of the 8 x 8 blocks of the 8 rows below the horizon (rows h/2 .. h/2 + 7; row 0 the top).
inline std::vector<double> far_floor_blocks(const Film& film) {
  std::vector<double> blocks;
  const int width = film.width(), top = film.height() / 2;
  for (int bx = 0; bx < width / 8; ++bx) {
    double sum = 0;
    for (int y = top; y < top + 8; ++y)
      for (int x = 8 * bx; x < 8 * bx + 8; ++x) sum += film.mean(x, y).g;
    blocks.push_back(sum / 64.0);
  }
  return blocks;
}

// The root mean square of a - b (the same length).
inline double rms_difference(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0;
  for (size_t i = 0; i < a.size(); ++i) s += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(s / static_cast<double>(a.size()));
}

}  // namespace kozu::test
