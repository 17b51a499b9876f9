// The film accumulates per-pixel sums of radiance samples. Each pixel keeps its own sample count,
// so a render stopped at any moment (time limit) is still a correct per-pixel average. Sums are in
// double precision: summation order is fixed by sample index, so results are bit-identical for
// any thread count. Per-channel sums of squares give a per-pixel variance estimate.
#pragma once

#include "core/color.h"

#include <vector>

namespace kozu {

class Film {
 public:
  Film() = default;
  Film(int width, int height);

  int width() const { return width_; }
  static size_t bytes_per_pixel();  // memory of one pixel's accumulators
  int height() const { return height_; }

  // Not thread-safe per pixel: the renderer gives each pixel to one thread at a time.
  void add_sample(int x, int y, const Rgb& L) {
    Pixel& p = pixels_[index(x, y)];
    p.sum += Vec3d(L);
    p.sum_sq += Vec3d(L) * Vec3d(L);
    ++p.count;
  }
  void add_discarded(int x, int y) { ++pixels_[index(x, y)].discarded; }

  Rgb mean(int x, int y) const;
  // Variance of the pixel mean (sample variance / count), per channel.
  Rgb variance_of_mean(int x, int y) const;
  uint32_t count(int x, int y) const { return pixels_[index(x, y)].count; }
  uint32_t discarded(int x, int y) const { return pixels_[index(x, y)].discarded; }

  // Row-major RGB floats of the per-pixel means. A pixel without a valid sample (a render stopped before
  // reaching it, or all its samples discarded) is filled from its sampled neighbours by pull-push
  // interpolation (Gortler et al. 1996, "The Lumigraph", §3.3): averaged up a 2× pyramid, then interpolated
  // bilinearly back down into the holes only. Black only when no pixel has a sample.
  std::vector<float> rgb() const;

  struct Summary {
    uint32_t min_spp = 0, max_spp = 0;
    double mean_spp = 0;
    uint64_t total_samples = 0;
    uint64_t discarded_samples = 0;
    uint64_t pixels_with_discarded = 0;
    uint64_t unsampled_pixels = 0;  // pixels without a valid sample, filled by rgb()
  };
  Summary summary() const;

 private:
  size_t index(int x, int y) const { return static_cast<size_t>(y) * width_ + x; }
  struct Pixel {
    Vec3d sum{0.0};
    Vec3d sum_sq{0.0};
    uint32_t count = 0;
    uint32_t discarded = 0;
  };
  int width_ = 0, height_ = 0;
  std::vector<Pixel> pixels_;
};

}  // namespace kozu
