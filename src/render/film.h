// The film accumulates per-pixel sums of radiance samples. Each pixel keeps its own sample count,
// so a render stopped at any moment (time limit) is still a correct per-pixel average. Sums are in
// double precision: summation order is fixed by sample index, so results are bit-identical for
// any thread count. Per-channel sums of squares give a per-pixel variance estimate.
//
// A film may cover a window of a larger image (`--crop`): pixels are addressed in image coordinates, and the
// film holds those of [origin, origin + size).
#pragma once

#include "core/color.h"
#include "core/huge_pages.h"
#include "integrators/integrator.h"
#include "render/emission_sums.h"

#include <cstdint>
#include <utility>
#include <vector>

namespace kozu {

// A pixel's visible emission estimated apart from its samples (Film::set_emission_apart): row-major index over the
// film's window, the estimate and the variance of that estimate, per channel.
struct ApartEmission {
  uint32_t index = 0;
  Vec3 value{0.0f}, variance{0.0f};
};

class Film {
 public:
  Film() = default;
  Film(int width, int height, Vec2i origin = Vec2i(0));

  int width() const { return width_; }
  static size_t bytes_per_pixel();  // memory of one pixel's accumulators
  int height() const { return height_; }
  Vec2i origin() const { return origin_; }

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
  // Samples the pixel has completed, valid or discarded: its next sample index, relative to the first.
  uint32_t taken(int x, int y) const {
    const Pixel& p = pixels_[index(x, y)];
    return p.count + p.discarded;
  }

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

  // The exact accumulators, row-major over the film's window: what a checkpoint stores and MPI reduces.
  struct Pixel {
    Vec3d sum{0.0};
    Vec3d sum_sq{0.0};
    uint32_t count = 0;
    uint32_t discarded = 0;
  };
  const PixelBuffer<Pixel>& pixels() const { return pixels_; }
  PixelBuffer<Pixel>& pixels() { return pixels_; }
  // Pixel i (row-major over the window) without any sample: its accumulators, features and coverage zeroed.
  void clear_pixel(size_t i);

  // Feature sums (AOVs, the denoiser's guides), kept only once enabled: one per completed sample (valid or
  // discarded, so a pixel's feature count is its taken()), in sample order. Also the sum of the even-numbered valid
  // samples: with the film's sum, the two half buffers of the denoiser. 44 bytes a pixel. Beside them, sparsely
  // (EmissionSums), the visible emission (PixelFeatures::emission) summed over the samples that went into the film,
  // with the even ones' share and the sum of its squared luminance: the denoiser's split and its refinement's choice.
  // The world position (12 bytes a pixel) only once enable_positions() (the `position` AOV): the denoisers do not
  // read it.
  struct FeaturePixel {
    Vec3 albedo{0.0f}, normal{0.0f};
    float depth = 0.0f;
    Vec3 even_sum{0.0f};
    uint32_t even_count = 0;
  };
  void enable_features() {
    features_.resize(pixels_.size());
    emission_ = EmissionSums(width_, height_);
  }
  bool has_features() const { return !features_.empty(); }
  // "ltc"'s per-pixel memory (PixelMemory: 56 bytes a pixel), kept by the film so that checkpoints carry it; the render
  // enables it where its integrator learns from neighbouring pixels, and the job releases it once no checkpoint needs
  // it.
  void enable_memory() { memory_.assign(pixels_.size(), PixelMemory{}); }
  bool has_memory() const { return !memory_.empty(); }
  void release_memory() { PixelBuffer<PixelMemory>().swap(memory_); }
  // The sample count at which the memory was last pooled (render/renderer.h; 0: never).
  int memory_pooled_at() const { return memory_pooled_at_; }
  void set_memory_pooled_at(int done) { memory_pooled_at_ = done; }
  const PixelBuffer<PixelMemory>& memory() const { return memory_; }
  PixelBuffer<PixelMemory>& memory() { return memory_; }
  // Position sums, beside the features (which must be enabled too).
  void enable_positions() { positions_.resize(pixels_.size()); }
  bool has_positions() const { return !positions_.empty(); }
  // `even`: the sample's value when it went into the film and its index is even, else null. `f.emission` must be
  // zero for a sample that did not go into the film.
  void add_features(int x, int y, const PixelFeatures& f, const Rgb* even) {
    const size_t i = index(x, y);
    FeaturePixel& p = features_[i];
    if (even) {
      p.even_sum += Vec3(even->r, even->g, even->b);
      ++p.even_count;
    }
    if (f.emission.r != 0.0f || f.emission.g != 0.0f || f.emission.b != 0.0f) {
      const Vec3 e(f.emission.r, f.emission.g, f.emission.b);
      EmissionSums::Pixel& q = emission_.at(x - origin_.x, y - origin_.y);
      if (even) q.even += e;
      q.sum += e;
      const float lum = luminance(f.emission);
      q.sq += lum * lum;
    }
    p.albedo += Vec3(f.albedo.r, f.albedo.g, f.albedo.b);
    p.normal += f.normal;
    p.depth += f.depth;
    if (!positions_.empty()) positions_[i] += f.position;
  }
  // The means over the pixel's samples (the position when kept, else zero; the normal is the mean, not
  // renormalized: its length shows how much the normals under the pixel agree); background when the pixel has none.
  PixelFeatures features(int x, int y) const;
  const PixelBuffer<FeaturePixel>& feature_pixels() const { return features_; }
  PixelBuffer<FeaturePixel>& feature_pixels() { return features_; }
  const EmissionSums& emission_sums() const { return emission_; }
  EmissionSums& emission_sums() { return emission_; }
  const PixelBuffer<Vec3>& position_sums() const { return positions_; }
  PixelBuffer<Vec3>& position_sums() { return positions_; }

  // Coverage (`--alpha`), kept only once enabled: per pixel, how many of its valid samples' camera rays hit a
  // surface. An integer count beside the sample count, so alpha = hits / count is exact, survives checkpoints,
  // MPI's sum and kozu merge (which recovers the integer from alpha x count) bit for bit.
  void enable_alpha() { hits_.resize(pixels_.size()); }
  bool has_alpha() const { return !hits_.empty(); }
  void add_hit(int x, int y) { ++hits_[index(x, y)]; }
  const PixelBuffer<uint32_t>& hit_counts() const { return hits_; }
  PixelBuffer<uint32_t>& hit_counts() { return hits_; }
  // Row-major alpha over the film's window: float(hits / count) in double precision; a pixel without a valid
  // sample is filled from its neighbours as rgb() fills the colour. Zero everywhere when coverage is not kept.
  std::vector<float> alpha() const;

  // The visible emission supersampled apart (render/emission_supersampling.h): the chosen pixels (row-major
  // indices over the window, ascending, each once) and their estimates. From then on those pixels' samples go into
  // the film without their visible emission (the renderer asks emission_apart), and mean() and rgb() add the
  // estimate back, variance_of_mean() its variance. Set once, before the first sample; emission_decided() holds from
  // then on, even when no pixel was chosen.
  void set_emission_apart(std::vector<ApartEmission> values);
  bool emission_decided() const { return emission_decided_; }
  bool emission_apart(int x, int y) const { return !apart_.empty() && apart_[index(x, y)]; }
  const std::vector<ApartEmission>& emission_apart_values() const { return apart_values_; }

 private:
  // Pixel i's supersampled visible emission when it is set apart, else null.
  const ApartEmission* apart_value(size_t i) const;
  // Fills the pixels without a valid sample in a row-major RGB image of the window from their sampled neighbours.
  void fill_unsampled(std::vector<float>& rgb) const;
  size_t index(int x, int y) const {
    return static_cast<size_t>(y - origin_.y) * width_ + static_cast<size_t>(x - origin_.x);
  }
  int width_ = 0, height_ = 0;
  Vec2i origin_{0};
  PixelBuffer<Pixel> pixels_;
  PixelBuffer<FeaturePixel> features_;
  EmissionSums emission_;
  PixelBuffer<Vec3> positions_;
  PixelBuffer<uint32_t> hits_;
  PixelBuffer<PixelMemory> memory_;
  int memory_pooled_at_ = 0;
  bool emission_decided_ = false;
  std::vector<uint8_t> apart_;               // per pixel, only once some pixel is apart
  std::vector<ApartEmission> apart_values_;  // sorted by pixel
};

}  // namespace kozu
