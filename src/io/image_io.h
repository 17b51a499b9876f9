// Image files through OpenImageIO. Writes go to a temporary file in the target folder that is
// renamed into place, so a failed or interrupted write never leaves a half-written image.
#pragma once

#include "core/color.h"
#include "render/tonemap.h"

#include <filesystem>
#include <string>
#include <vector>

namespace kozu {

struct Image {
  int width = 0, height = 0, channels = 0;
  std::vector<float> data;  // row-major, channels interleaved, linear
  // Three channels: grey is replicated, extra channels (alpha) are dropped.
  std::vector<Rgb> to_rgb() const;
};

// Throws InputError(file, "", reason) if the file cannot be read.
Image read_image(const std::filesystem::path& file);

// Output format from the extension: .exr and .hdr store linear float RGB; .png and .jpg store
// tone-mapped 8-bit sRGB. Throws std::runtime_error naming the file on failure.
void write_image(const std::filesystem::path& file, int width, int height, const std::vector<float>& rgb,
                 const ToneMap& tonemap);

bool is_supported_output(const std::filesystem::path& file);

}  // namespace kozu
