// Supersampling of the visible emission (PixelFeatures::emission: emitters the camera sees directly or through
// perfectly specular vertices) at the pixels where it varies, for the raw image.
//
// Where a bright emitter's edge, a thin emissive line or a light's reflection in a mirror crosses a pixel, the pixel's
// value is the emitter's radiance times the share of the pixel it covers, and the render's samples estimate that
// share coarsely: in bench/cycles' Cornell box (256², 64 spp) 37 % of the image's variance is in the 0.1 % of pixels
// on the light's edge, in its emitters scene 88 % in 1 % of the pixels. Those pixels need many more camera rays, not
// more paths, and the paths that compute only the visible emission (Integrator::visible_emission: a camera ray and
// its specular chain, no light sampling) cost a fraction of a full one. So, before the render:
//
// 1. A pilot: `pilot_samples` full samples per pixel (1: a 1/spp share of the render), from a sample stream of
//    its own, each split into its visible emission and the rest.
// 2. The choice: pixels whose 3 × 3 neighbourhood's pilot luminances of the visible emission differ by more than
//    `relative_jump` of their largest (an edge runs through or beside them) and by more than twice those of the
//    rest (where the surface beside the emitter is about as bright, splitting adds variance instead), the largest
//    differences first, as many as the budget allows: each takes k = factor × spp visible-emission samples
//    (within [min_samples, max_samples]), all of them together at most budget × spp × the window's pixels.
// 3. Each chosen pixel's visible emission estimated from its k samples, from a third stream, with the variance of
//    that estimate (Film::variance_of_mean adds it).
//
// The render then takes the chosen pixels' samples without their visible emission (Film::emission_apart) and the
// image adds the estimate back (Film::rgb, Film::mean). Both estimates are unbiased and the choice depends on the
// pilot alone, independent of either, so the image stays unbiased (tests/render/test_emission_supersampling.cpp).
// Under MPI every rank makes the same choice over the whole window (it depends on the seed, the scene and the window
// alone, at any thread count), so the reduced film is the single process's. Not used where the film keeps the
// denoiser's features (the denoiser splits the visible emission itself: render/emission_refine.h), with checkpoints
// (a checkpoint holds sums, not the choice: render/job.cpp), or below min_spp samples a pixel.
//
// A render bounded by time alone (spp 0 and a deadline: --time-limit, a job's budget) has no sample count to plan
// for, so the pilot's own time stands in: the samples a pixel the time left would allow at the pilot's pace (its
// full samples cost what the render's will). Below min_spp nothing is chosen, and the pilot gives up once it has
// used, or its first rows project it to use, more than 1 / (min_spp + 1) of the time. The choice then also depends
// on the machine's speed, as the sample count of such a render does; it stays independent of both estimates, so the
// image stays unbiased.
#pragma once

#include "integrators/integrator.h"
#include "render/film.h"
#include "scene/render_settings.h"
#include "scene/scene.h"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

namespace kozu {

struct EmissionSupersamplingSettings {
  int min_spp = 16;  // renders of fewer samples a pixel do without (the pilot would cost too large a share)
  int pilot_samples = 1;
  int factor = 8;
  int min_samples = 64;
  int max_samples = 16384;
  double budget = 0.25;
  float relative_jump = 0.5f;
};

struct EmissionSupersamplingStats {
  int spp = 0;           // the render's samples a pixel the choice planned for (under a deadline, the pilot's guess)
  uint64_t pixels = 0;   // pixels whose visible emission was supersampled
  uint64_t samples = 0;  // visible-emission samples taken, pilot included
  double seconds = 0.0;
  RayCounters rays;
};

// Whether a render of `film` with these settings supersamples: asked for, not yet decided for this film, before its
// first sample, without the denoiser's features, with at least settings.min_spp samples a pixel to take, or none
// set and a deadline (has_deadline) to plan by.
bool emission_supersampling_applies(const Film& film, const RenderSettings& options,
                                    const EmissionSupersamplingSettings& settings = {}, bool has_deadline = false);

// The chosen pixels (row-major indices over the film's window, ascending) and their visible emission. Runs on the
// calling thread's task arena; stops early when `stop` rises, returning only the pixels it finished (possibly
// none), so a stopped pass never leaves a pixel apart without its value.
std::vector<ApartEmission> supersample_emission(const Scene& scene, const Integrator& integrator, const Film& film,
                                                const RenderSettings& options, const std::atomic<bool>& stop,
                                                const EmissionSupersamplingSettings& settings = {},
                                                EmissionSupersamplingStats* stats = nullptr,
                                                std::optional<std::chrono::steady_clock::time_point> deadline = {});

}  // namespace kozu
