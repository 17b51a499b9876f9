// kozu's built-in denoiser (`kozu render --denoise`): a feature-guided non-local-means filter on two half
// buffers, after Rousselle, Knaus and Zwicker 2012 ("Adaptive rendering with non-local means filtering", §4: the
// variance-cancelling patch distance) and Rousselle, Manzi and Zwicker 2013 ("Robust denoising using feature and
// color information": feature weights, and filtering each half buffer with weights from the other so that a
// pixel's noise does not pick its own neighbours).
//
// For pixel p and each neighbour q in a (2r+1)² window, with u the half buffer's colour and V the variance of its
// mean, estimated from the two halves' difference, V = |A − B|² / 2 averaged over a 3 × 3 box (Rousselle et al.
// 2012's "buffer variance"): kozu's stratified samples make the sample variance / count overstate the error, ~16×
// at antialiased edges, which let the filter average edge pixels of different coverage:
//   d²(p, q) = mean over the (2f+1)² patch and the channels of [(u_p − u_q)² − (V_p + min(V_p, V_q))] / (ε + k²(V_p +
//   V_q)) w(p, q)  = exp(−max(0, d²)) · exp(−|a_p − a_q|²/σ_a² − |n_p − n_q|²/σ_n² − ((z_p − z_q)/(σ_z z_p))²)
// with the first surface's albedo a, normal n and depth z (render/aov.h). Buffer A is filtered with the weights of
// buffer B's colours and B with A's; the output is their mean.
//
// The filtered radiance leaves out the visible emission (light from emitters seen directly or through perfectly
// specular vertices): its noise is the coverage of the emitters' edges, which no filter over neighbours recovers;
// it is added back unfiltered, re-estimated where its samples disagree (render/emission_refine.h).
//
// Two windows are filtered (radius r and a narrow one) and each pixel takes the one whose estimated error is lower
// (Rousselle et al. 2012 §5): Stein's unbiased risk estimate (Stein 1981) per half, |F_k − y_k|² − V + 2 V
// ∂F_k/∂y_k, where ∂F_k/∂y_k is the pixel's own weight over the weights' sum (exact here: half k's weights come
// from the other half's colours, so they do not depend on y_k), averaged over both halves and a (2R+1)² box.
// Parameters, the measured error and speed: docs/production.md. The implementation (denoiser.cpp) holds the buffers as
// planes of floats and runs each step over a row's pixels, so that the compiler vectorizes it.
#pragma once

#include "render/emission_refine.h"
#include "render/film.h"

#include <functional>
#include <vector>

namespace kozu {

// Defaults chosen on the Cornell box (256²) and the demo (320 × 180) at 16 spp against 1024-spp references
// (docs/production.md): patch 5 × 5 over 3 × 3 lowered the error by 8 % and 22 %; k above 0.45 raised it.
struct DenoiseSettings {
  int radius = 10;       // window (2r+1)²
  int radius_small = 2;  // the narrow window, chosen where its risk is lower
  int risk_radius = 4;   // the risk estimate averaged over (2R+1)²
  int patch = 2;         // patch (2f+1)²
  float k = 0.45f;       // colour distance scale (larger: smoother)
  float sigma_albedo = 0.05f;
  float sigma_normal = 0.2f;
  float sigma_depth = 0.03f;  // relative
  int band_rows = 0;          // rows per band of the image filtered at a time (0: about 192); the output does not depend on it
};

// The denoised image of the film's window, row-major RGB. The film must keep features (Film::enable_features).
// The visible emission (PixelFeatures::emission) is left out of the filtered radiance and added back where
// `emission` says so (refine_emission's; visible_emission(film) when null).
// `expired` (optional) is polled between bands of rows of the wide window: once it says true the wide window is
// abandoned and every pixel from that band on takes the narrow one (a twentieth of the cost, computed first), so a
// denoiser that runs out of time degrades instead of overrunning.
// `risk` (optional) receives each pixel's estimated squared error: the SURE of the window it took (per channel,
// averaged over the risk box; may be negative where the estimate is).
std::vector<float> denoise(const Film& film, const DenoiseSettings& settings = {},
                           const VisibleEmission* emission = nullptr, const std::function<bool()>& expired = {},
                           std::vector<float>* risk = nullptr);

}  // namespace kozu
