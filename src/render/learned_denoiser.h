// kozu's learned denoiser: a small convolutional U-Net in the spirit of Intel Open Image Denoise's (Áfra 2019) and
// of Chaitanya, Kaplanyan, Schied, Salvi, Lefohn, Nowrouzezahrai and Aila 2017, "Interactive reconstruction of Monte
// Carlo image sequences using a recurrent denoising autoencoder" (SIGGRAPH), without the recurrence. Its weights are
// trained by tools/denoiser/train.py (PyTorch) on pairs of noisy and converged images kozu renders itself
// (tools/denoiser/make_data.py); here the network only runs, on the CPU with oneDNN.
//
// Graph (every convolution 3 × 3, stride 1, zero padding 1, with bias; widths c0..c3, d0..d2 read from the weights,
// PyTorch's nn.Conv2d(in, out, 3, padding=1), nn.MaxPool2d(2), nn.Upsample(scale_factor=2, mode='nearest') and
// torch.cat([up, skip], 1)):
//   L0 conv 9 → c0, ReLU;  L1 conv c0 → c0, ReLU = skip0            full resolution
//   max-pool 2 × 2;  L2 conv c0 → c1, ReLU = skip1                    1/2
//   max-pool;        L3 conv c1 → c2, ReLU = skip2                    1/4
//   max-pool;        L4 conv c2 → c3, ReLU                            1/8
//   upsample 2×, concat [up, skip2];  L5 conv c3 + c2 → d2, ReLU      1/4
//   upsample,    concat [up, skip1];  L6 conv d2 + c1 → d1, ReLU      1/2
//   upsample,    concat [up, skip0];  L7 conv d1 + c0 → d0, ReLU      full resolution
//   L8 conv d0 → 3, no activation
// Input: 9 channels per pixel, the transformed colour (3), the albedo (3) and the normal (3); output: the transformed
// colour (3).
//
// Colour transform (UnetTransform; tools/denoiser/train.py reimplements it and must match it exactly):
//   c    = the radiance with negative and non-finite values as 0
//   lum  = 0.2126 r + 0.7152 g + 0.0722 b
//   s    = clamp(0.18 / exp(mean over the whole image's pixels of log(lum + 1e-4)), 1e-4, 1e4)   (exposure; the
//          mean is accumulated in double precision; not per tile)
//   in   = log1p(s c) per channel;   albedo clamped to [0, 1];   normal as given (non-finite components as 0)
//   out  = expm1(max(y, 0)) / s per channel
//
// Tiling: the network runs on tiles of at most `tile` × `tile` output pixels (a multiple of 8), each read with an
// overlap of 32 pixels on every side, of which only the core is kept, so memory stays bounded whatever the image.
// A core pixel's output depends on the input within 31 pixels of it (the receptive field of the graph above on the
// 8-pixel grid), so with tile origins on multiples of 8 (the max-pool grids align with the whole image's) a pixel's
// output does not depend on the tiling, up to the rounding of the convolutions' sums. Pixels of a tile outside the
// image take the nearest image pixel's values (clamp to edge). One set of oneDNN primitives is built for the tile
// size and reused for every tile; the weights are reordered into the primitives' layouts once.
//
// Deadline: `expired` (optional) is polled before each tile; once it says true the remaining tiles keep the input
// radiance unfiltered (negative and non-finite values as 0), so a denoiser that runs out of time degrades instead of
// overrunning.
//
// Weights ("kzw", little-endian): the 8 bytes "KZUNET01", uint32 layer count (9), then per layer uint32 out, in and
// k (3), out·in·k·k float32 weights in PyTorch's OIHW order and out float32 biases; then the 4 bytes "END!". The
// trained file, data/denoiser/unet-v1.kzw, is compiled into the library when it exists at configure time.
#pragma once

#include "render/emission_refine.h"
#include "render/film.h"

#include <array>
#include <cstddef>
#include <functional>
#include <vector>

namespace kozu {

struct UnetLayer {
  int out = 0, in = 0;         // channels
  std::vector<float> weights;  // out · in · 3 · 3, OIHW
  std::vector<float> bias;     // out
};

struct UnetWeights {
  static constexpr int kLayers = 9;
  std::array<UnetLayer, kLayers> layers;
};

// The widths of the graph's distinct layers: the encoder's c0 (L0, L1), c1 (L2), c2 (L3), c3 (L4) and the decoder's
// d2 (L5), d1 (L6), d0 (L7).
struct UnetWidths {
  int c0, c1, c2, c3, d2, d1, d0;
};
// The nine layers of a graph of these widths: channels in and out as the graph chains them, weights and biases sized
// and zero (what a trainer or a test fills in).
UnetWeights unet_layers(const UnetWidths& widths);

// Parses a "kzw" file's bytes. Throws std::runtime_error naming what is wrong: the magic, the layer count, a kernel
// size, a channel count (0 or above 512), truncated data, trailing bytes, a non-finite weight or bias, or widths
// that do not chain as the graph above needs.
UnetWeights parse_unet_weights(const unsigned char* data, size_t size);

// Throws std::runtime_error unless the layers' widths chain as the graph above needs (9 inputs, L1 keeping c0, each
// concatenation's sum, 3 outputs) and each layer holds its weights and biases.
void validate_unet_weights(const UnetWeights& weights);

// The weights compiled in from data/denoiser/unet-v1.kzw, parsed once. Throws std::runtime_error when the file was
// not there when the build was configured.
const UnetWeights& builtin_unet_weights();

// The colour transform shared with the trainer (the formulas in the comment at the top).
struct UnetTransform {
  float scale = 1.0f;  // s
  // The exposure of an image: `rgb` holds `pixels` RGB triplets.
  static UnetTransform of_image(const float* rgb, size_t pixels);
  // The same a part at a time: `sum` accumulates the parts' log luminances in pixel order, of_sum takes the total.
  static void add_log_luminance(const float* rgb, size_t pixels, double& sum);
  static UnetTransform of_sum(double sum, size_t pixels);
  // The radiance sanitised (negative and non-finite values as 0).
  static float sanitize(float c);
  float encode(float c) const;  // log1p(s · sanitize(c))
  float decode(float y) const;  // expm1(max(y, 0)) / s; non-finite results as 0
};

struct UnetSettings {
  int tile = 256;   // the largest core of a tile, in pixels on a side; a positive multiple of 8
  int threads = 0;  // OpenMP threads for oneDNN (omp_set_num_threads, restored after); 0: OpenMP's default
};

// The network's denoised radiance of a w × h image. color, albedo and normal hold w · h · 3 floats each, row-major
// RGB; the result likewise, with every value finite and non-negative. Throws std::invalid_argument on sizes that do
// not match or a tile size that is not a positive multiple of 8, std::runtime_error on weights that do not chain
// (validate_unet_weights) or a primitive oneDNN cannot build or run.
std::vector<float> run_unet(const UnetWeights& weights, int w, int h, const std::vector<float>& color,
                            const std::vector<float>& albedo, const std::vector<float>& normal,
                            const UnetSettings& settings = {}, const std::function<bool()>& expired = {});

// The denoised image of the film's window, row-major RGB, as denoise_regression (render/feature_regression.h): the
// network filters the mean of the two half buffers without the visible emission, with the film's albedo and
// normal, and the visible emission is added back unfiltered (`emission`, or the film's own when null). The film
// must keep features. The first form runs the built-in weights (and throws as builtin_unet_weights does).
std::vector<float> denoise_learned(const Film& film, const VisibleEmission* emission = nullptr,
                                   const std::function<bool()>& expired = {}, const UnetSettings& settings = {});
std::vector<float> denoise_learned(const UnetWeights& weights, const Film& film,
                                   const VisibleEmission* emission = nullptr, const std::function<bool()>& expired = {},
                                   const UnetSettings& settings = {});

}  // namespace kozu
