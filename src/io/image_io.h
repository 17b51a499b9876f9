// Image files through OpenImageIO. Writes go to a temporary file in the target folder that is
// renamed into place, so a failed or interrupted write never leaves a half-written image.
#pragma once

#include "core/color.h"
#include "core/tonemap.h"

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

// The most pixels an input image may have (16384 x 16384); larger headers are refused before any allocation.
inline constexpr uint64_t kMaxImagePixels = uint64_t{1} << 28;

// Reads the first (up to) four channels as float. Throws InputError(file, "", reason) if the file cannot be
// read, its header claims more than kMaxImagePixels or more memory than is left, or it is truncated.
Image read_image(const std::filesystem::path& file);

// Output format from the extension: .exr and .hdr store linear float RGB; .png and .jpg store
// tone-mapped 8-bit sRGB. Throws std::runtime_error naming the file on failure.
void write_image(const std::filesystem::path& file, int width, int height, const std::vector<float>& rgb,
                 const ToneMap& tonemap);

bool is_supported_output(const std::filesystem::path& file);

}  // namespace kozu
