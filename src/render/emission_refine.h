// Re-estimation of the visible emission (PixelFeatures::emission: light from emitters the camera sees directly or
// through perfectly specular vertices) where a pixel's samples disagree on it, for the denoiser.
//
// At the edge of an emitter seen directly (or in a mirror, or through smooth glass) a pixel's value is the
// emitter's radiance times the share of the pixel it covers, and a few samples estimate that share coarsely: at
// 16 stratified samples the error of a bright light's edge pixels is most of a denoised image's squared error, and
// no filter over neighbouring pixels can recover a sub-pixel coverage it was never shown. The denoiser therefore
// filters the radiance without the visible emission and adds the visible emission back unfiltered, re-estimated
// here with many more of the cheap paths that compute only it (PathIntegrator::visible_emission: a camera ray and
// its specular chain, no light sampling). Rousselle, Knaus and Zwicker 2012 ("Adaptive rendering with non-local
// means filtering") likewise spend samples where the filter cannot help.
//
// Which pixels: those whose visible emission's standard error (from the film's per-pixel sums of its luminance and
// squared luminance) exceeds `relative_error` of their luminance, the largest variances first, as long as the
// samples spent stay within `samples_per_pixel` × the window's pixels, so the cost is bounded whatever the
// image shows (a textured emitter, a sky behind leaves). A chosen pixel takes `factor` × its own sample count,
// within [min_samples, max_samples], from its own sample streams: indices sample_begin, sample_begin + 1, …, so its
// first samples are those the render took and the refined value is deterministic for a seed at any thread count.
// A pixel whose visible emission is that noisy but was not chosen keeps it in the filtered radiance, which smooths
// the noise the filter can (glass choosing between reflection and refraction) as it did before the split.
#pragma once

#include "integrators/integrator.h"
#include "render/film.h"
#include "scene/render_settings.h"
#include "scene/scene.h"

#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

namespace kozu {

struct EmissionRefineSettings {
  int factor = 8;
  int min_samples = 64;
  int max_samples = 4096;
  double samples_per_pixel = 4.0;  // the whole pass's samples, per pixel of the window
  float relative_error = 0.01f;
};

struct EmissionRefineStats {
  uint64_t pixels = 0;   // pixels re-estimated
  uint64_t samples = 0;  // visible-emission samples taken
  double seconds = 0.0;
};

// Per pixel of the film's window, row-major: whether the denoiser filters the radiance without the visible emission
// (apart) and the visible emission it then adds back: the film's own mean, or the re-estimate of a refined pixel.
// A byte a pixel and the refined pixels' values alone (a full-image value would be 12 bytes a pixel more, 25 MB
// at 1920 × 1080); it reads the film it was made from, which must outlive it.
class VisibleEmission {
 public:
  VisibleEmission() = default;
  // Every pixel apart, at the film's mean (the film must keep features).
  explicit VisibleEmission(const Film& film);

  size_t size() const { return state_.size(); }
  bool apart(size_t i) const { return state_[i] != kInRadiance; }
  Vec3 value(size_t i) const;
  // Pixel i left in the filtered radiance.
  void keep_in_radiance(size_t i) { state_[i] = kInRadiance; }
  // Pixel i apart, at v.
  void set(size_t i, const Vec3& v);

 private:
  enum : uint8_t { kInRadiance, kFilmMean, kRefined };
  const Film* film_ = nullptr;
  std::vector<uint8_t> state_;
  std::vector<std::pair<uint32_t, Vec3>> refined_;  // sorted by pixel
};

// From the film alone: apart, at the film's own mean, where its standard error is within relative_error.
VisibleEmission visible_emission(const Film& film, const EmissionRefineSettings& settings = {});

// As above, and the noisy pixels chosen within the budget re-estimated and apart. The film must keep features
// (Film::enable_features). `expired` (optional; --budget's deadline) is polled before each pixel: once it says true
// the pixels not yet begun are left as visible_emission leaves them (noisy ones in the filtered radiance), so a
// machine slower than the budget's calibration said does not carry the pass past the deadline.
VisibleEmission refine_emission(const Scene& scene, const Integrator& integrator, const Film& film,
                                const RenderSettings& options, const EmissionRefineSettings& settings = {},
                                EmissionRefineStats* stats = nullptr, const std::function<bool()>& expired = {});

}  // namespace kozu
