// The height field behind a tangent-space normal map, by relaxation refined coarse to fine through a mip chain.
//
// D. Chan, "Material Advances in Call of Duty: WWII", SIGGRAPH 2018 course Advances in Real-Time Rendering in
// Games, §4.1–4.2 and Algorithm 5.
//
// Equation map:
//   slopes g from the normal map      normal_slopes: g = (-n_x / n_z, +n_y / n_z) per texel, in image axes
//                                     (x right, y down: the renderer's OpenGL maps have +y towards +v, up the image)
//   relaxation (§4.2)                 each texel's height from its four neighbours' heights plus the height
//                                     differences the slopes give across the shared edges (the Gauss-Seidel step
//                                     of the discrete Poisson equation lap(h) = div(g)), red-black order
//   Algorithm 5                       height_from_slopes: the slopes averaged down a mip chain (2 x 2 boxes,
//                                     wrapping), solved at the coarsest level, each solution upsampled (bilinear,
//                                     wrapping) as the first guess of the next finer level, relaxed there
//   "impossible" maps (§4.1)          slope_residual: RMS of g - grad(h) over RMS g, on the texel edges: the share
//                                     of the map that no height field has (its curl part); 0 for a true gradient
//
// Discretisation: heights sit at texel centres; the height difference across the edge between two neighbours is
// the mean of their slopes (trapezoid rule), so relaxation minimises the squared misfit over all edges. The
// texture repeats, so every neighbour wraps. Heights are in texel widths (a slope is a height difference per
// texel), and the result has mean zero (the Poisson problem fixes the height up to a constant).
//
// Parameters (HeightFromNormalsOptions): Gauss-Seidel sweeps at each finer level after upsampling (default 64);
// at the coarsest level (default at most 8 texels a side) sweeps until the largest change is below `tolerance`
// (1e-6 texel widths) or `coarsest_sweeps` (2000), over-relaxed by `omega` (1.9: the same fixed point in fewer sweeps;
// the finer levels use plain Gauss-Seidel, which damps the high frequencies that upsampling leaves); correction
// V-cycles after the pass (`vcycles`, default 2; 3 + 3 sweeps a level).
//
// Deviations: the paper picks texels at random; red-black order is the deterministic, parallel equivalent
// (lexicographic where a size is odd, since the wrap then joins texels of one colour). Algorithm 5's single
// coarse-to-fine pass leaves the lowest frequencies of a large map partly unconverged; the V-cycles solve the level-0
// residual on the same chain (the coarse levels then solve for the error, not the height). vcycles = 0 is the
// paper's single pass.
#pragma once

#include <cstdint>
#include <vector>

namespace kozu {

struct SlopeField {
  int width = 0, height = 0;
  std::vector<float> gx, gy;  // dh/dx (x right) and dh/dy (y down, row 0 = the image's top), row-major
};

// The slopes of a tangent-space normal map stored as colours c in [0, 1] (n = 2c - 1, OpenGL: green up), as
// src/materials/normal_map.cpp reads them; `channels` values per texel (>= 3). flip_y for DirectX (green down)
// maps. Normals with n_z below `min_nz` (near-horizontal or below the surface) are clamped there, so that a
// slope stays finite (1e-2: slopes up to 100).
SlopeField normal_slopes(const float* texels, int width, int height, int channels, bool flip_y = false,
                         float min_nz = 1e-2f);

struct HeightFromNormalsOptions {
  int sweeps_per_level = 64;
  int coarsest_sweeps = 2000;
  double tolerance = 1e-6;  // largest change of a sweep at the coarsest level, in texel widths
  double omega = 1.9;       // over-relaxation; 1 is plain Gauss-Seidel
  int coarsest_size = 8;
  int vcycles = 2;
};

struct HeightField {
  int width = 0, height = 0;
  std::vector<float> h;  // row-major, row 0 = the image's top, in texel widths, mean zero
};

// Algorithm 5: the height field whose gradient is closest (least squares over the texel edges) to the slopes.
HeightField height_from_slopes(const SlopeField& g, const HeightFromNormalsOptions& options = {});

// RMS over the texel edges of (height difference - trapezoid slope), over the RMS of the trapezoid slopes: the
// part of the map that is not a gradient. 0 when every slope is 0.
double slope_residual(const SlopeField& g, const HeightField& h);

// The normal map a height field gives (central differences, wrapping), encoded as colours (n + 1) / 2, RGB, OpenGL
// convention: the inverse of normal_slopes up to discretisation, for tests and for the occlusion's normals.
std::vector<float> normals_from_height(const HeightField& h, float height_scale = 1.0f);

}  // namespace kozu
