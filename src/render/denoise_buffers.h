// The denoisers' view of a film (render/denoiser.h, render/feature_regression.h): its two half buffers (the even
// and the odd samples' means) without the visible emission, the variance of a half's mean estimated from their
// difference, and the first surface's features.
#pragma once

#include "render/emission_refine.h"
#include "render/film.h"

#include <vector>

namespace kozu::denoise_detail {

inline constexpr float kUnknownVariance = 1e6f;  // pixels without samples in both halves

// Rows [y0, y1) of the image (w × h); pixel (x, y) at index(x, y).
struct Buffers {
  int w = 0, h = 0;
  int y0 = 0, y1 = 0;
  size_t index(int x, int y) const { return static_cast<size_t>(y - y0) * w + x; }
  std::vector<Vec3> half[2];  // the even and the odd samples' means
  std::vector<float> var;     // variance of one half's mean, averaged over the channels (both halves alike)
  std::vector<Vec3> albedo, normal;
  std::vector<float> depth;
};

// The mean of v over the (2R+1)² box around each pixel (clipped at the borders).
std::vector<float> box_mean(const std::vector<float>& v, int w, int h, int R);

// The visible emission a denoiser leaves out and adds back: `given`, or else the film's own (visible_emission,
// computed into `own`). Throws std::logic_error naming `who` when the film keeps no features or `given` does not
// hold one value per pixel.
const VisibleEmission& emission_to_add_back(const Film& film, const VisibleEmission* given, VisibleEmission& own,
                                            const char* who);

// The half buffers of the radiance without the visible emission (emission_refine.h), which is added back after.
Buffers split(const Film& film, const VisibleEmission& emission);
// split's buffers a band of rows at a time, for filters whose memory should follow a band, not the image.
class HalfBufferRows {
 public:
  // Keeps film.rgb() (holes filled from their neighbours) only when some pixel has no sample.
  HalfBufferRows(const Film& film, const VisibleEmission& emission);
  // Rows [y0, y1) (clipped to the image) of split(film, emission), the same values bit for bit.
  Buffers rows(int y0, int y1) const;

 private:
  const Film& film_;
  const VisibleEmission& emission_;
  std::vector<float> filled_;
};

// Output pixel i (RGB at 3 i): the filtered radiance plus the visible emission where it was left out, non-finite
// values as 0 and negative ones clamped.
void put_pixel(std::vector<float>& out, size_t i, const Vec3& filtered, const VisibleEmission& emission);

}  // namespace kozu::denoise_detail
