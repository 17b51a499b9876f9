// Progressive, tiled rendering with TBB.
//
// The image is rendered in passes; each pass adds a few samples to every pixel, tile by tile in
// parallel. Pixel (x, y) always receives samples 0, 1, 2, ... in order, each drawn from the
// sampler stream (seed, pixel, sample index), and each pixel is touched by one thread at a time,
// so the image is bit-identical for any thread count and any pass schedule. With a time limit
// the render stops at the deadline, between samples; each pixel keeps its own sample count.
#pragma once

#include "integrators/integrator.h"
#include "render/film.h"
#include "render/scene.h"

#include <atomic>
#include <chrono>
#include <functional>

namespace kozu {

struct RenderOptions {
  int spp = 64;             // target samples per pixel; 0 = until the time limit
  double time_limit = 0.0;  // seconds, 0 = none
  int threads = 0;          // 0 = all hardware threads
  uint64_t seed = 0;
  int tile_size = 16;
  PixelFilter::Type filter = PixelFilter::Type::Gaussian;
};

struct RenderProgress {
  std::atomic<uint64_t> samples_done{0};  // pixel samples finished so far
  std::atomic<bool> cancel{false};        // set by another thread to stop early
};

struct RenderResult {
  double seconds = 0;  // wall time of the sampling loop
  RayCounters rays;
  uint64_t paths = 0;
  int threads = 0;
  bool hit_time_limit = false;
  Film::Summary film;
};

RenderResult render(const Scene& scene, const Integrator& integrator, Film& film, const RenderOptions& options,
                    RenderProgress* progress = nullptr);

}  // namespace kozu
