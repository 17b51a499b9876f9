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
  std::vector<float> data;  // row-major, channels interleaved, as stored (8-bit values scaled to [0, 1])
  int source_bits = 32;        // bits per channel in the file
  bool source_is_float = true;  // the file stores floating-point values (EXR, HDR, float TIFF)
  // Three channels: grey is replicated, extra channels (alpha) are dropped.
  std::vector<Rgb> to_rgb() const;
};

// The most pixels an input image may have (16384 x 16384); larger headers are refused before any allocation.
inline constexpr uint64_t kMaxImagePixels = uint64_t{1} << 28;

// Reads the first (up to) four channels as float. Throws InputError(file, "", reason) if the file cannot be
// read, its header claims more than kMaxImagePixels or more memory than is left, or it is truncated.
Image read_image(const std::filesystem::path& file);

// What an image file's header says, read with read_image's checks (no pixels are decoded).
struct ImageInfo {
  int width = 0, height = 0, channels = 0;
  int bits = 8;           // bits per channel
  bool is_float = false;  // floating-point values
  bool tiled = false;
  int mip_levels = 1;  // resolution levels stored in the file (a mip-mapped texture has several)
};
ImageInfo probe_image(const std::filesystem::path& file);

// Output format from the extension: .exr and .hdr store linear float RGB; .png and .jpg store
// tone-mapped 8-bit sRGB. Throws std::runtime_error naming the file on failure.
void write_image(const std::filesystem::path& file, int width, int height, const std::vector<float>& rgb,
                 const ToneMap& tonemap);

bool is_supported_output(const std::filesystem::path& file);

}  // namespace kozu
