// The --budget's reserve (render/job.h): what finishing a frame costs after sampling (the image writes, measured
// here and now; a checkpoint; the denoiser; the statistics and the exit), so that sampling ends when what is left of
// the budget is what the writes need (docs/production.md).
#pragma once

#include "core/math.h"
#include "core/tonemap.h"
#include "render/denoiser_kind.h"
#include "render/emission_refine.h"
#include "render/film.h"
#include "render/output_paths.h"

#include <functional>
#include <vector>

namespace kozu::render_job {

// The visible emission's re-estimation before the filter, at most 4 samples per pixel: 1.6 us per pixel on a quiet
// 2-core machine (docs/production.md), scaled by the measured slowdown. The filter's own cost is measured
// (denoise_seconds).
constexpr double kEmissionRefineSecondsPerPixel = 1.6e-6;

// Under --budget EXR outputs are written uncompressed: zip gains about 10 % on a render's noisy floats and takes ten
// times as long (a 4K image: 3 s against 0.3 s), time the budget gives to sampling instead.
constexpr const char* kBudgetExrCompression = "none";

// What finishing an image output costs here and now, in seconds for `pixels` (calibrated by writing two small
// images into the output's folder); `slowdown` takes the largest measured cost per pixel over the floor's.
// `extra_channels`: the EXR's channels besides RGB (alpha, AOVs), written in the calibration too.
double write_seconds(const OutputFile& o, const ToneMap& tonemap, double pixels, int extra_channels, double* slowdown);

// Seconds that finishing a frame takes after sampling, with margin: the --budget reserve, in three parts.
struct FinishCost {
  double raw = 0.0;              // the raw images (every image output when the denoiser is skipped) and a checkpoint
  double denoised = 0.0;         // the denoiser and the writes of the denoised images
  double denoised_writes = 0.0;  // the writes of the denoised images alone: what the filter must leave
  double fixed = 0.0;            // the statistics, the exit and the scheduler
  double filter = 0.0;           // the filter's expected seconds, without margin (part of `denoised`)
  double refine = 0.0;           // of which the visible emission's re-estimation (render/emission_refine.h)
  double total(bool denoise) const { return raw + fixed + (denoise ? denoised : 0.0); }
};
FinishCost finish_seconds(Vec2i size, const std::vector<OutputFile>& outputs, const ToneMap& tonemap, bool checkpoint,
                          bool denoise, bool denoise_only, DenoiserKind denoiser, int extra_channels);

// What the denoiser's filter costs here and now for `pixels`, in seconds: the filter run on a synthetic 160 x 90
// film with features (the U-Net: 192 x 96, whose 32-pixel tile overlap makes it cost more per pixel than a full
// image's tiles, a margin), timed, per pixel (at least the floor measured on a quiet 2-core machine) times the
// pixels. `slowdown` takes the measured cost over the floor's.
double denoise_seconds(double pixels, DenoiserKind denoiser, double* slowdown);

// The chosen filter on the film (the one dispatch for the calibration above and the frame's denoised image):
// `emission` and `expired` as the filters take them, `threads` for the U-Net's OpenMP (0: its default).
std::vector<float> run_denoiser(DenoiserKind denoiser, const Film& film, const VisibleEmission* emission = nullptr,
                                const std::function<bool()>& expired = {}, int threads = 0);

}  // namespace kozu::render_job
