// `--denoiser ensemble` (docs/production.md): NL-means (render/denoiser.h) and the first-order feature regression
// (render/feature_regression.h) run on the same film, each pixel weighted by the other filter's estimated error. Both
// filters estimate their own error to choose their windows (NL-means: Stein's unbiased risk estimate of the window it
// took; the regression: its cross-validated risk), each averaged over its risk box. For two unbiased estimates with
// independent errors of variances r1 and r2, the weight w1 = r2 / (r1 + r2) on the first gives the least error,
// r1 r2 / (r1 + r2), below either's (inverse-variance weighting). The filters' errors are largely independent:
// NL-means leaves stains where its patches match noise, the regression noise where its fit in the features fails.
#pragma once

#include "render/emission_refine.h"
#include "render/film.h"

#include <functional>
#include <vector>

namespace kozu {

// The weighted image of the film's window, row-major RGB, with the visible emission added back as the two filters
// add it (`emission`: refine_emission's, or visible_emission(film) when null). `expired` as the filters take it;
// past the deadline after NL-means its image is returned alone and the regression does not start.
std::vector<float> denoise_ensemble(const Film& film, const VisibleEmission* emission = nullptr,
                                    const std::function<bool()>& expired = {});

}  // namespace kozu
