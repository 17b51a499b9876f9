// Adaptive sampling (render.noise_threshold): which pixels have converged and take no more samples.
//
// A pixel's error estimate is the standard error of its Rec. 709 luminance mean (from the film's per-channel sums
// of squares, channels taken as independent) over the square root of max(luminance, 0.01): Cycles' normalization
// (Blender's adaptive sampling), which weighs noise roughly as a display transform shows it, so that dark pixels do
// not take the samples a relative error would give them. Pixels with fewer than min_spp samples have no estimate.
//
// A pixel converges when its estimate and those of its 8 neighbours are at most the threshold (Cycles dilates its
// unconverged pixels the same way): a pixel whose few samples all fell on one side of an edge beside it (the sliver
// of a light's edge that none of 64 samples met) shows no variance, but its neighbour on the edge does. Without the
// neighbourhood, such pixels stopped at min_spp on the Cornell box and its linear error at equal time rose 60 %
// (docs/production.md). A converged pixel stays converged.
//
// The check reads the film between passes, on the rendering thread; what it decides depends only on the film's
// contents, so it is the same for any thread count. Pixels another process renders (MPI's tiles) are left out of
// their neighbours' test: under MPI, pixels beside another rank's tiles may stop at other pass boundaries than in
// one process.
#pragma once

#include "render/film.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace kozu {

class AdaptiveSampling {
 public:
  // `mine`: whether this process renders image pixel p (its tiles); the film's window is checked.
  AdaptiveSampling(const Film& film, float threshold, int min_spp, std::function<bool(Vec2i)> mine);

  // Re-checks every pixel of this process's tiles; true when all of them have converged.
  bool update(const Film& film);
  bool converged(int x, int y) const { return converged_[index(x, y)] != 0; }
  // The error estimate of image pixel (x, y) at the last update (+inf below min_spp samples).
  float error(int x, int y) const { return error_[index(x, y)]; }

  // The estimate from a pixel's mean and the variance of that mean.
  static float estimate(const Rgb& mean, const Rgb& variance_of_mean);

 private:
  size_t index(int x, int y) const {
    return static_cast<size_t>(y - origin_.y) * static_cast<size_t>(size_.x) + static_cast<size_t>(x - origin_.x);
  }
  Vec2i origin_, size_;
  float threshold_;
  int min_spp_;
  std::vector<uint8_t> mine_, converged_;
  std::vector<float> error_;
};

}  // namespace kozu
