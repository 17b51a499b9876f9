// The training passes of path guiding ("guiding": "on"), run before a frame's own samples.
//
// Müller, Gross, Novák 2017, "Practical Path Guiding for Efficient Light-Transport Simulation" §4.3: passes of
// doubling size, each guided by the field the passes before it learnt and recording into it, the field refined after
// each (integrators/guiding_field.h). Pass k takes 2^k samples of every other pixel in x and y (a quarter of the
// pixels this process renders: the field learns from the paths' vertices in the scene, which the skipped pixels'
// neighbours reach as well). The passes stop before their samples would pass kTrainingShare of the render's own
// (spp × pixels), and under a time limit or a deadline before the next pass (twice the last one's time) would pass
// kTrainingShare of the time left.
//
// Deviation: the paper keeps the last pass's image, weighted against the others by their variance; kozu leaves every
// training sample out of the image. Its film is the exact mean of samples 0, 1, 2, … of each pixel, all drawn with one
// final field, so a render with a sample count is bit-identical at any thread count, pass schedule or resume
// (a resumed render trains the same field again), at a cost under kTrainingShare of the samples.
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
  uint64_t paths = 0;  // the training passes' samples
  double seconds = 0;
  size_t leaves = 0, directional_nodes = 0, bytes = 0;
};

// Trains field for the frame whose film (its window, and options' tile rank) and settings are given: the integrator
// samples and records with the field during the passes, and is left sampling with it (recording off). Stops early on
// progress->cancel.
GuidingTraining train_guiding(const Scene& scene, PathIntegrator& integrator, GuidingField& field, const Film& film,
                              const RenderSettings& options, RenderProgress* progress = nullptr);

}  // namespace kozu
