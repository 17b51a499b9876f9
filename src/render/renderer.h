// Progressive, tiled rendering with TBB.
//
// The image is rendered in passes; each pass adds a few samples to every pixel, tile by tile in
// parallel. Pixel (x, y) always receives samples 0, 1, 2, ... in order, each drawn from the
// sampler stream (seed, pixel, sample index), and each pixel is touched by one thread at a time,
// so the image is bit-identical for any thread count and any pass schedule.
//
// The first sample of every pixel is taken coarse to fine (every 8th pixel in x and y, then every 4th, 2nd and
// the rest), so a render stopped early has samples spread over the whole image; pixels still without one are
// filled from their neighbours when the image is written (render/fill.h).
//
// Stopping: a watchdog thread raises one stop flag at the deadline or when RenderProgress::cancel is set (a
// signal); the pixel loop and the path's own long loops poll it (core/path_budget.h), and a sample that was
// running when the flag rose is discarded. So a stop holds within milliseconds whatever one sample costs, and
// every pixel stays the exact mean of its completed samples.
#pragma once

#include "integrators/integrator.h"
#include "render/emission_supersampling.h"
#include "render/film.h"
#include "scene/filter.h"
#include "scene/scene.h"

#include <atomic>
#include <chrono>
#include <functional>
#include <optional>
#include <span>
#include <vector>

namespace kozu {

// The most worker threads a render uses: 4 × the hardware threads (more only adds contention).
int max_render_threads();
// The worker threads a render with these settings uses (options.threads, else all cores; at most the above).
int render_threads(const RenderSettings& options);

// PixelMemory (integrators/integrator.h): each pixel of the width × height memories learns what its eight
// neighbours' samples saw (learnt_light, learnt_share: their pooled sums), never what its own saw. Neighbours that saw
// different lights teach nothing. Whether it skips the control variate weighs what the control variate removed from
// the neighbours' variance against image_variance (pixel_memory_variance). `other` gives the memory of a neighbour the
// window's memories do not hold (outside it, or another part's: null where none; empty: every neighbour is in the
// window). The renderer calls it once, when every pixel has taken PixelMemory::kPilotSamples.
void pool_pixel_memory(std::span<PixelMemory> memory, int width, int height, double image_variance,
                       const std::function<const PixelMemory*(int x, int y)>& other = {});
// The image's mean variance of one sample within a pixel, from those memories (in their order, so deterministic):
// the renderer's pool takes it over the pixels of the lattice every kPixelMemoryLattice pixels of the image (0, 0
// included), so that every part of a split render finds the same value.
double pixel_memory_variance(const std::vector<const PixelMemory*>& memories);
constexpr int kPixelMemoryLattice = 8;

struct RenderProgress {
  std::atomic<uint64_t> samples_done{0};  // pixel samples finished so far
  std::atomic<bool> cancel{false};        // set by another thread (or a signal handler) to stop early
  // An absolute end of sampling besides the time limit (`--budget`: fixed before the render's own set-up, so that
  // set-up counts against it).
  std::optional<std::chrono::steady_clock::time_point> deadline;
};

// The render's deadline: options.time_limit from start, or progress's deadline, whichever comes first; none without
// either.
std::optional<std::chrono::steady_clock::time_point> render_deadline(const RenderSettings& options,
                                                                     const RenderProgress* progress,
                                                                     std::chrono::steady_clock::time_point start);

// One worker thread's state in a render: its arena, sampler and counters.
struct RenderThreadState {
  Arena arena;
  Sampler sampler;
  RayCounters rays;
  uint64_t paths = 0;
  explicit RenderThreadState(uint32_t seed) : sampler(seed) {}
};

// "direct": "ltc"'s pixel memories at the render's end (PixelMemory): how much of the image its control variate
// took part in. Zero where the integrator keeps none.
struct ControlVariateStats {
  uint64_t pixels = 0;          // pixels with a sample and a memory
  uint64_t pixels_taking = 0;   // of which took it and still do (the neighbours' samples did not say skip: learnt_skip)
  double samples = 0.0;         // their samples
  double samples_taking = 0.0;  // of which took the control variate at a vertex
};

struct RenderResult {
  double seconds = 0;  // wall time of the sampling loop
  RayCounters rays;    // also counts paths truncated by the per-path work cap
  uint64_t paths = 0;  // completed samples (valid or discarded as non-finite); stopped samples excluded
  int threads = 0;     // worker threads actually used
  bool hit_time_limit = false;
  bool cancelled = false;  // RenderProgress::cancel stopped it
  Film::Summary film;
  EmissionSupersamplingStats emission;  // the visible emission supersampled before the samples (its rays in `rays`)
  ControlVariateStats control_variate;
};

// Work done between passes, while no sample runs (so the film is consistent): partial images and checkpoints.
// Passes are kept short enough (an estimate from the last pass) that `every` runs about every `interval` seconds.
struct PassHook {
  double interval = 0.0;        // seconds; 0 = never
  std::function<void()> every;  // called on the rendering thread, at most once per interval
};

// Renders the film's window (the whole image, or a crop). Each pixel continues from the samples the film already
// holds (film.taken: a resumed checkpoint), starting at options.sample_begin, up to options.spp; so a resumed
// render is bit-identical to one never stopped.
RenderResult render(const Scene& scene, const Integrator& integrator, Film& film, const RenderSettings& options,
                    RenderProgress* progress = nullptr, const PassHook& hook = {});

// The sampler's seed for a render's seed, and the camera ray of sample s of pixel (x, y): the sampler is started
// at (x, y, s) and left positioned after the camera's numbers, where the integrator goes on.
uint32_t sampler_seed(const RenderSettings& options);
Ray camera_sample(const Scene& scene, const PixelFilter& filter, Sampler& sampler, int x, int y, int s);

// The film's rules for a sample: whether it counts (finite, and non-negative unless the integrator's samples are
// signed), and the factor render.clamp scales it by (its largest component down to the bound, keeping its hue; 1
// when off or within it).
bool sample_counts(const Rgb& L, bool signed_samples);
float clamp_factor(const Rgb& L, float clamp);

// Sample s of pixel (x, y)'s visible emission alone (Integrator::visible_emission), under those rules: clamped, or
// nothing when the film would discard it. The re-estimate for the denoiser and the supersampling for the raw image
// take their samples so.
std::optional<Rgb> visible_emission_sample(const Scene& scene, const Integrator& integrator, const PixelFilter& filter,
                                           const RenderSettings& options, RenderThreadState& st, int x, int y, int s,
                                           const StopFlag& stop);

// Whether image pixel p lies in a tile this process renders (options.tile_rank of tile_ranks) in the film's window.
bool renders_pixel(const Film& film, const RenderSettings& options, Vec2i p);

}  // namespace kozu
