// kozu's fast denoiser (`--denoise --denoiser regression`): first-order feature regression in the spirit of
// Bitterli, Rousselle, Moon, Iglesias-Guitián, Adler, Mitchell, Jarosz and Novák 2016, "Nonlinearly Weighted
// First-order Regression for Denoising Monte Carlo Renderings" (NFOR, EGSR), and of the guided filter (He, Sun and
// Tang 2013), made O(1) per pixel with box windows.
//
// For a window ω of (2r+1)² pixels centred on pixel i, the radiance is modelled as a first-order function of the
// first surface's features f = (normal, log depth, albedo luminance) (render/aov.h):
//   y(q) ≈ ȳ + aᵀ (f(q) − f̄),   a = (Cov_ω f + λ I)⁻¹ Cov_ω(f, y)          (NFOR eq. 6 with uniform weights)
// and the estimate at i is the fit there, F(i) = ȳ + aᵀ (f(i) − f̄). Every window sum is a box filter of per-pixel
// products (running sums: the cost does not grow with r). The radiance is demodulated first, y = c / (albedo + ε),
// and the fit multiplied back by the pixel's own (albedo + ε): a texture is then kept, whatever its detail, wherever
// the light over the window is smooth (the usual practice of production denoisers); the albedo's luminance among
// the features takes up what ε leaves of the texture (c / (a + ε) still rises a little with a).
//
// Each half buffer (the even and the odd samples, render/denoise_buffers.h) is fitted on its own, so the other is
// an independent check (NFOR §4, cross-validation): E|F_A − B|² = E|F_A − μ|² + Var B, so the squared error of a
// window size at a pixel is estimated by ½ (|F_A − B|² + |F_B − A|²) − V, averaged over a (2R+1)² box. Window radii
// 0 (the pixel itself), 1, 3, 7 and 15 are tried, smallest first, and each pixel blends them by
// exp(−(risk − least risk) / (τ V̄)) (V̄ the noise variance averaged like the risks, τ = 0.1: nearly the least, but a
// near tie does not flip a pixel between windows, which reads as speckle): large windows where the features explain
// the image (walls, floors, textured surfaces), small ones at what they do not (shadow edges, caustics, reflections).
// The blend is accumulated as the candidates come (a running weighted sum rescaled when the least risk drops), so
// it costs no memory per candidate. The output is the mean of the two halves' fits. The visible
// emission is filtered apart and added back as in the NL-means filter (render/denoiser.h).
//
// Deadline: `expired`, polled between bands of rows, stops the search; the pixels keep the best window found so far
// (the raw pixel at worst), so a denoiser that runs out of time degrades instead of overrunning.
//
// Deviations from NFOR: uniform window weights instead of NL-means weights (what makes it O(1) per pixel), one
// set of features without their own filtering, and hard selection per pixel instead of the per-pixel weighted
// combination of several bandwidths.
#pragma once

#include "render/emission_refine.h"
#include "render/film.h"

#include <functional>
#include <vector>

namespace kozu {

struct RegressionSettings {
  std::vector<int> radii = {1, 3, 7, 15};  // besides 0 (the pixel), smallest first
  int risk_radius = 3;                     // the error estimates averaged over (2R+1)²
  float ridge = 1e-4f;                     // λ: keeps flat regions (zero feature variance) solvable
  float albedo_floor = 0.02f;              // ε of the demodulation
  bool select = true;                      // false: the last radius everywhere (no choice; for comparisons)
  float softness = 0.1f;  // τ: candidates blended by exp(−(risk − least) / (τ V̄)); 0: the least only
  int band_rows = 0;      // rows per band of the image filtered at a time (0: 192); the output does not depend on it
};

// The denoised image of the film's window, row-major RGB (as denoise() in render/denoiser.h). The film must keep
// features. `expired` (optional) is polled between bands of rows: once it says true the search stops there; the band
// it stopped in keeps the windows it finished, the bands after take each pixel's own mean (radius 0). `risk`
// (optional) receives each pixel's estimated squared error, the least candidate's cross-validated risk (per channel,
// the noise variance subtracted, averaged over the risk box; may be negative where the estimate is).
std::vector<float> denoise_regression(const Film& film, const RegressionSettings& settings = {},
                                      const VisibleEmission* emission = nullptr,
                                      const std::function<bool()>& expired = {}, std::vector<float>* risk = nullptr);

}  // namespace kozu
