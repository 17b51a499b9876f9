#include "render/adaptive_sampling.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace kozu {

AdaptiveSampling::AdaptiveSampling(const Film& film, float threshold, int min_spp, std::function<bool(Vec2i)> mine)
    : origin_(film.origin()), size_(film.width(), film.height()), threshold_(threshold), min_spp_(min_spp) {
  const size_t n = static_cast<size_t>(size_.x) * static_cast<size_t>(size_.y);
  mine_.resize(n);
  converged_.assign(n, 0);
  error_.assign(n, std::numeric_limits<float>::infinity());
  for (int y = origin_.y; y < origin_.y + size_.y; ++y)
    for (int x = origin_.x; x < origin_.x + size_.x; ++x) mine_[index(x, y)] = mine(Vec2i(x, y));
}

float AdaptiveSampling::estimate(const Rgb& m, const Rgb& v) {
  constexpr double kFloor = 0.01;
  const double lum = 0.2126 * m.r + 0.7152 * m.g + 0.0722 * m.b;
  const double var = 0.2126 * 0.2126 * v.r + 0.7152 * 0.7152 * v.g + 0.0722 * 0.0722 * v.b;
  return static_cast<float>(std::sqrt(var / std::max(std::abs(lum), kFloor)));
}

bool AdaptiveSampling::update(const Film& film) {
  const Vec2i hi = origin_ + size_;
  for (int y = origin_.y; y < hi.y; ++y)
    for (int x = origin_.x; x < hi.x; ++x) {
      const size_t i = index(x, y);
      if (!mine_[i]) continue;
      error_[i] = static_cast<int>(film.count(x, y)) < min_spp_
                      ? std::numeric_limits<float>::infinity()
                      : estimate(film.mean(x, y), film.variance_of_mean(x, y));
    }
  bool all = true;
  for (int y = origin_.y; y < hi.y; ++y)
    for (int x = origin_.x; x < hi.x; ++x) {
      const size_t i = index(x, y);
      if (!mine_[i]) continue;
      if (!converged_[i]) {
        bool ok = true;
        for (int ny = std::max(origin_.y, y - 1); ny <= std::min(hi.y - 1, y + 1); ++ny)
          for (int nx = std::max(origin_.x, x - 1); nx <= std::min(hi.x - 1, x + 1); ++nx) {
            const size_t j = index(nx, ny);
            ok = ok && (!mine_[j] || error_[j] <= threshold_);
          }
        converged_[i] = ok;
      }
      all = all && converged_[i];
    }
  return all;
}

}  // namespace kozu
