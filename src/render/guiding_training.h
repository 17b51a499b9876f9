// Path guiding's training ("guiding": "on"): the passes that learn the field, and the render that uses it.
//
// Müller, Gross, Novák 2017, "Practical Path Guiding for Efficient Light-Transport Simulation" §4.3: passes of
// doubling size, each guided by the field the passes before it learnt and recording into it, the field refined after
// each (integrators/guiding_field.h), until what is left of the budget is less than twice the last pass.
//
// render_guided: the passes are the image's own first samples. Pass k takes samples 2^k − 1 .. 2^(k+1) − 2 of every
// pixel, so which field drew a sample depends on its index alone, and the image is still bit-identical for any
// thread count and pass schedule. Passes continue while the samples left after the next one are at least twice its
// size (with a sample count), or while the time left is at least three times its predicted length (under a time limit
// or deadline); the rest of the budget renders with the last field. Deviation: the paper weighs the passes' images by
// their inverse variance; kozu's film is the plain mean of each pixel's samples, so the early passes' samples (a
// sixteenth of them at 64 spp, with the least trained fields) weigh as much as the others.
//
// train_guiding: passes on the side, their samples left out of the image: for a film that already holds samples (a
// resumed checkpoint) or a sample range that does not start at 0, whose first samples are not rendered here. Pass k
// takes 2^k samples of every other pixel in x and y, while the passes' samples stay within kTrainingShare of the
// render's and, under a time limit, their time within kTrainingShare of the time left. A resumed render is unbiased
// but not bit-identical to one never stopped (its later samples use the side-trained field).
//
// MPI: each rank trains its own field on its own tiles, with no communication: the fields differ between ranks but
// each is unbiased, and a rank never waits for the others.
#pragma once

#include "integrators/guiding_field.h"
#include "integrators/path.h"
#include "render/film.h"
#include "render/renderer.h"

#include <cstdint>

namespace kozu {

inline constexpr double kTrainingShare = 0.125;

struct GuidingTraining {
  int passes = 0;
  bool in_image = false;  // the passes' samples are the image's first ones (render_guided), not on the side
  int samples = 0;        // per pixel (in_image), or per trained pixel
  uint64_t paths = 0;     // the training passes' samples
  double seconds = 0;
  size_t leaves = 0, directional_nodes = 0, bytes = 0;
};

// Trains field for the frame whose film (its window, and options' tile rank) and settings are given: the integrator
// samples and records with the field during the passes, and is left sampling with it (recording off). Stops early on
// progress->cancel.
GuidingTraining train_guiding(const Scene& scene, PathIntegrator& integrator, GuidingField& field, const Film& film,
                              const RenderSettings& options, RenderProgress* progress = nullptr);

// render() (render/renderer.h) with path guiding: the training passes as the image's first samples (on the side where
// the film already holds samples or options.sample_begin > 0), then the rest with the learnt field. The result sums
// the passes' (seconds from the first pass's start); `training` gets the passes' figures.
RenderResult render_guided(const Scene& scene, PathIntegrator& integrator, GuidingField& field, Film& film,
                           const RenderSettings& options, RenderProgress* progress, const PassHook& hook,
                           GuidingTraining* training);

}  // namespace kozu
