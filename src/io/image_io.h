// Image files through OpenImageIO. Writes go to a temporary file in the target folder that is
// renamed into place, so a failed or interrupted write never leaves a half-written image.
#pragma once

#include "core/color.h"
#include "core/tonemap.h"

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace kozu {

struct Image {
  int width = 0, height = 0, channels = 0;
  std::vector<float> data;      // row-major, channels interleaved, as stored (8-bit values scaled to [0, 1])
  int source_bits = 32;         // bits per channel in the file
  bool source_is_float = true;  // the file stores floating-point values (EXR, HDR, float TIFF)
  // Filled by read_image_all: every channel's name, the data window's origin inside the display window (an EXR
  // of a --crop render), the display window's size, and the kozu:* attributes of a kozu EXR.
  std::vector<std::string> channel_names;
  Vec2i origin{0}, full_size{0};
  std::vector<std::pair<std::string, std::string>> attributes;
  // Its 4x4 float matrix attributes (OpenEXR's worldToCamera, worldToNDC), row-major as stored.
  std::vector<std::pair<std::string, std::array<float, 16>>> matrices;
  // Three channels: grey is replicated, extra channels (alpha) are dropped.
  std::vector<Rgb> to_rgb() const;
};

// The most pixels an input image may have (16384 x 16384); larger headers are refused before any allocation.
inline constexpr uint64_t kMaxImagePixels = uint64_t{1} << 28;

// Reads the first (up to) four channels as float. Throws InputError(file, "", reason) if the file cannot be
// read, its header claims more than kMaxImagePixels or more memory than is left, or it is truncated.
Image read_image(const std::filesystem::path& file);

// Every channel (at most kMaxImageChannels) with its name, the windows and kozu's attributes: for `kozu merge`.
inline constexpr int kMaxImageChannels = 64;
Image read_image_all(const std::filesystem::path& file);

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

// What an EXR holds besides the colour: named float channels (AOVs, "albedo.R", "N.X", "Z", ...), string
// attributes (kozu's render metadata, "kozu:spp", ...) and a data window inside a larger display window (a crop).
// Other formats keep the colour of the data window only.
struct ImageExtras {
  std::vector<std::string> channels;
  std::vector<float> data;  // row-major, channels.size() values per pixel
  std::vector<std::pair<std::string, std::string>> attributes;
  std::vector<std::pair<std::string, std::array<float, 16>>> matrices;  // M44f attributes (worldToCamera, ...)
  Vec2i origin{0};                                                      // of the data window
  Vec2i full_size{0};                                                   // the display window; 0: the image's own size
};
void write_image(const std::filesystem::path& file, int width, int height, const std::vector<float>& rgb,
                 const ToneMap& tonemap, const ImageExtras& extras);

bool is_supported_output(const std::filesystem::path& file);

}  // namespace kozu
