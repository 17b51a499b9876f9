// Files for normal and gloss mip filtering (textures/normal_gloss_filter.h): reads a tangent-space normal map and a
// gloss map (or one gloss value), runs Chan 2018's Algorithm 3 and writes the normal and gloss mip chains as tiled
// files with explicit mip levels (OpenEXR .exr, or TIFF .tx / .tif), which the texture system reads level by level.
//
// Normal maps: OpenGL convention (x along +u, y along +v, z out of the surface), any bit depth or float, decoded
// n = 2 c - 1 as the renderer decodes them (materials/normal_map.cpp); two channels are x, y with z = sqrt(1 - x^2 -
// y^2) (BC5-style). The output normal map is encoded the same way, c = (n + 1) / 2, three float channels; the gloss
// map is one float channel. Gloss files are read as data: the first channel, values in [0, 1].
#pragma once

#include "io/image_io.h"
#include "textures/normal_gloss_filter.h"

#include <filesystem>
#include <vector>

namespace kozu {

struct NormalGlossFilterJob {
  std::filesystem::path normal_map;
  std::filesystem::path gloss_map;  // empty: gloss_value at every texel
  double gloss_value = 1.0;
  // The renderer's normal_map_strength s (materials/normal_map.h): a texel's x and y scaled by s before it is
  // normalised, so that the chain filters the normals the renderer would shade with.
  double strength = 1.0;
  std::filesystem::path out_normal, out_gloss;
  ShortenedNormalModel model = ShortenedNormalModel::Macro;
};

struct NormalGlossFilterSummary {
  int width = 0, height = 0, levels = 0;
  double mean_gloss_level0 = 0, mean_gloss_last = 0;  // the authored gloss's mean and the 1 x 1 level's gloss
};

// Throws InputError naming the file (unreadable input, sizes that differ, a gloss outside [0, 1], a normal of zero
// length, not enough memory) or std::runtime_error naming an output that cannot be written. Outputs are written
// atomically (a temporary file renamed into place).
NormalGlossFilterSummary filter_normal_gloss_files(const NormalGlossFilterJob& job);

// Writes `levels` (level 0 first, each floor(w / 2) x floor(h / 2) of the one before, down to 1 x 1, all with the
// same channels) as one tiled, mip-mapped float file with explicit levels.
void write_mip_levels(const std::filesystem::path& file, const std::vector<Image>& levels);

// One mip level of a file (level 0 the finest), every channel as float; throws InputError when it has no such level.
Image read_mip_level(const std::filesystem::path& file, int level);

}  // namespace kozu
