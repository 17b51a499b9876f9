// An integrator estimates the radiance arriving along a camera ray.
#pragma once

#include "core/arena.h"
#include "core/color.h"
#include "core/path_budget.h"
#include "core/sampler.h"
#include "geometry/ray.h"

#include <cstdint>
#include <type_traits>

namespace kozu {

// Per-thread counters, summed by the renderer.
struct RayCounters {
  uint64_t camera_rays = 0;
  uint64_t extension_rays = 0;  // closest-hit rays after the first
  uint64_t shadow_rays = 0;
  uint64_t probe_rays = 0;       // BSSRDF probe queries (one per hit a probe segment steps through, plus one)
  uint64_t truncated_paths = 0;  // paths cut by PathBudget's cap (not rays; not in total())
  // Tentative collisions of free flights and ratio tracking in media (PathBudget steps; a homogeneous medium's
  // closed-form flight counts one): the work media cost, not rays, not in total().
  uint64_t tentative_collisions = 0;
  uint64_t total() const { return camera_rays + extension_rays + shadow_rays + probe_rays; }
  RayCounters& operator+=(const RayCounters& o) {
    camera_rays += o.camera_rays;
    extension_rays += o.extension_rays;
    shadow_rays += o.shadow_rays;
    probe_rays += o.probe_rays;
    truncated_paths += o.truncated_paths;
    tentative_collisions += o.tentative_collisions;
    return *this;
  }
};

// What the camera ray sees first, for AOVs and the denoiser's guides (render/aov.h): the first surface's albedo
// (one BSDF sample's weight f cos / pdf: an unbiased estimate of its directional albedo), shading normal facing the
// camera, world position and camera-space depth. A camera ray that scatters in a medium first reports that point
// with albedo 0 and normal 0; one that escapes reports zeros and depth kBackgroundDepth.
// `emission` is the part of the sample's radiance that came from emitters the camera sees directly or through
// perfectly specular vertices only (weight 1, no light sampling involved): the denoiser re-estimates it
// (render/emission_refine.h) instead of filtering it, since its noise is the emitters' edges' coverage.
struct PixelFeatures {
  static constexpr float kBackgroundDepth = 1e10f;  // as Blender's Z pass
  Rgb albedo{0.0f};
  Rgb emission{0.0f};
  Vec3 normal{0.0f};
  Vec3 position{0.0f};
  float depth = kBackgroundDepth;
  bool set = false;
};

// What a pixel's samples and its neighbours' taught, for an estimate whose coefficient may depend on anything but the
// sample's own numbers: "ltc"'s control-variate coefficient (path.cpp, integrators/ltc_direct.h), the share of the
// chosen polygon light's lobe-weighted light that shadow rays saw, Σ f̃ V / p over Σ f̃ / p. The renderer keeps one
// per pixel where the integrator asks (Integrator::pixel_memory) and hands a pixel's to its samples, one sample at a
// time. A sample adds what it saw to its own pixel's sums. Once every pixel has taken its first kPilotSamples, the
// renderer pools them once (render/renderer.h): each pixel learns what its eight neighbours' pilot samples saw, and
// its later samples read that. Never the pixel's own samples: their numbers are stratified against this sample's
// (core/sampler.h), so a coefficient learnt from them would be correlated with its directions and the control variate
// biased (measured: +0.05 % on scenes/ltc_rough.json); the neighbours' streams are independent of it. Learnt from the
// pilot samples alone, what a pixel reads depends on nothing but the pilots of its neighbourhood and of a fixed
// lattice of the image, which any part of a split render (--crop, --sample-range, MPI ranks) traces again: its pixels
// are the whole render's bit for bit. The film keeps the memories and a checkpoint carries them.
struct PixelMemory {
  // Lights by their place in the integrator's list of lights that may take the control variate, plus one (0: none),
  // not by address: a checkpoint carries the memory (render/checkpoint.h), so that a resumed render continues it and
  // its image is the uninterrupted render's bit for bit. Plain 4-byte fields, no padding: stored as they lie.
  // Names 1 .. kMaxLights (PathIntegrator::kMaxLtcLights).
  static constexpr uint32_t kMaxLights = 4;
  // The samples a pixel takes before the pool; a part of a split render traces these again for its pixels whose
  // film does not hold them, so its memories may have seen up to this many samples more than its film took.
  static constexpr int kPilotSamples = 2;

  uint32_t light = 0;         // the light this pixel's sums are of
  float seen = 0.0f;          // Σ f̃ V / p
  float all = 0.0f;           // Σ f̃ / p
  uint32_t learnt_light = 0;  // the light the neighbours saw (0: none, or not the same one)
  float learnt_share = 0.0f;  // and the share of it they saw
  // Whether the control variate pays. The pixel's samples' luminance (count, sum, sum of squares), and over those that
  // took the control variate (cv_samples) their luminance with it and without it: the same path's estimate less what
  // the control variates added, which is exactly "sample"'s estimate along that path (the control variate changes no
  // decision of the path). So the difference of the two variances is what it removed. At equal time the image's
  // squared error falls where that exceeds kCost times the image's mean variance of a sample, kCost being what the
  // control variate adds to a sample's time (its closed form and lobes: 0.1 to 0.4 of a sample of direct light
  // alone, measured in docs/lights.md); elsewhere it is skipped (learnt_skip).
  static constexpr float kCost = 0.3f;
  float samples = 0.0f, sum = 0.0f, sum2 = 0.0f;
  float cv_samples = 0.0f, with_sum = 0.0f, with_sum2 = 0.0f, without_sum = 0.0f, without_sum2 = 0.0f;
  uint32_t learnt_skip = 0;  // 0 or 1
};
static_assert(std::is_trivially_copyable_v<PixelMemory> && sizeof(PixelMemory) == 56,
              "a checkpoint stores PixelMemory as it lies: 14 four-byte fields");

class Integrator {
 public:
  virtual ~Integrator() = default;
  // One radiance sample along ray. The sampler is positioned at the pixel sample; the arena is
  // reset by the caller after the sample. Once `stop` is raised the path ends as soon as it polls it, and the
  // caller discards the sample.
  virtual Rgb li(const Ray& ray, Sampler& sampler, Arena& arena, RayCounters& counters, const StopFlag& stop) const = 0;
  // True when a sample may be negative and still be right on average (a control variate's estimate, as
  // path.cpp's "direct": "ltc"): the film keeps such samples instead of discarding them.
  virtual bool signed_samples() const { return false; }
  // One sample as li(), and the features of what the camera ray sees (the same sample: the radiance is the same
  // whether features are asked for or not).
  virtual Rgb li_features(const Ray& ray, Sampler& sampler, Arena& arena, RayCounters& counters, const StopFlag& stop,
                          PixelFeatures& features) const {
    features = PixelFeatures{};
    return li(ray, sampler, arena, counters, stop);
  }
  // Whether li_pixel's samples learn from the neighbouring pixels' earlier samples (PixelMemory).
  virtual bool pixel_memory() const { return false; }
  // One sample as li_features (features non-null) or li, with the pixel's memory (null: none kept).
  virtual Rgb li_pixel(const Ray& ray, Sampler& sampler, Arena& arena, RayCounters& counters, const StopFlag& stop,
                       PixelFeatures* features, PixelMemory* memory) const {
    (void)memory;
    return features ? li_features(ray, sampler, arena, counters, stop, *features)
                    : li(ray, sampler, arena, counters, stop);
  }
  // The features' `emission` alone, for the same sampler stream: the path ends at its first vertex that is not
  // perfectly specular, without light sampling, drawing the same numbers up to there as li_features, so the
  // first samples of a pixel give the values li_features recorded. Zero for integrators that record none.
  virtual Rgb visible_emission(const Ray& ray, Sampler& sampler, Arena& arena, RayCounters& counters,
                               const StopFlag& stop) const {
    (void)ray, (void)sampler, (void)arena, (void)counters, (void)stop;
    return Rgb(0.0f);
  }
};

}  // namespace kozu
