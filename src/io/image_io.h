// Image files through OpenImageIO. Writes go to a temporary file in the target folder that is
// renamed into place, so a failed or interrupted write never leaves a half-written image.
#pragma once

#include "core/color.h"
#include "core/tonemap.h"

#include <array>
#include <filesystem>
#include <mutex>
#include <string>
#include <utility>
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
// read_image_all without the pixels (data stays empty): what `kozu merge` checks of every part (windows, channels,
// attributes) before it allocates any pixel buffer.
Image read_image_header(const std::filesystem::path& file);
// The bytes read_image_all's pixels take (width x height x channels floats), from a header read by
// read_image_header.
inline uint64_t image_bytes(const Image& header) {
  return uint64_t(header.width) * uint64_t(header.height) * uint64_t(header.channels) * sizeof(float);
}

// Tiny negative values are normal in HDR files: the ringing of the resampling filters that made them. Every HDRI
// shipped with Blender 3.4 has some (measured: 3 to 8,980 of 1.57 million values, down to -0.00385, or 2.5 % of the
// image's mean in night.exr; together at most 6.2e-7 of the positive values' total). Such values are noise when
//   - together they are at most 1e-4 of the image's positive total (they cannot change what the image lights), and
//   - each is within 1e-3 of the image's largest value (ringing is a fraction of the brightest feature nearby),
// and then they are clamped to 0 with one warning; otherwise the image is refused, naming its most negative value:
// a signed image (a normal map, data in a colour slot) carries a large share of negative energy.
struct NegativeValues {
  uint64_t count = 0;
  double negative_sum = 0, positive_sum = 0;  // magnitudes, over the checked values
  double most_negative = 0, largest = 0;
  bool noise() const { return count == 0 || (negative_sum <= 1e-4 * positive_sum && -most_negative <= 1e-3 * largest); }
  // "the negative values carry 2.1e-02 of the image's energy; values down to -0.001 are clamped as filtering noise"
  std::string why_not_noise() const;
};
// Clamps the small negative values of the first `channels` channels of img (all when channels <= 0) to 0 and
// returns how many there were; throws InputError(file, "", ...) naming the first meaningfully negative value.
// `what` names the values in the message ("radiance", "a colour").
uint64_t clamp_small_negatives(Image& img, const std::filesystem::path& file, int channels, const std::string& what);
// The image loaders (environment maps, textures) run in parallel load jobs; the warnings they add to their scene
// object (JsonObject::warn, one vector per scene file) are added under this lock.
std::mutex& image_warning_mutex();

// What an image file's header says, read with read_image's checks (no pixels are decoded).
struct ImageInfo {
  int width = 0, height = 0, channels = 0;
  int bits = 8;           // bits per channel
  bool is_float = false;  // floating-point values
  bool tiled = false;
  int mip_levels = 1;                   // resolution levels stored in the file (a mip-mapped texture has several)
  int tile_width = 0, tile_height = 0;  // 0 for a scanline file
  uint64_t tile_bytes() const {         // one tile's pixels as stored
    return uint64_t(tile_width) * uint64_t(tile_height) * uint64_t(channels) * uint64_t(bits / 8);
  }
};
ImageInfo probe_image(const std::filesystem::path& file);

// What scan_image_values found in the first (up to) four channels of every resolution level of a file.
struct ImageScan {
  uint64_t values = 0;                       // values read (level 0 only)
  uint64_t nonfinite = 0;                    // NaN or infinite values, all levels
  uint64_t negative = 0;                     // values < 0 at level 0
  double sum = 0;                            // of the finite values at level 0
  double most_negative = 0;                  // the smallest value at level 0 (0 if none is negative)
  NegativeValues negatives;                  // level 0's negative values against its positive ones
  int x = 0, y = 0, level = 0, channel = 0;  // where the first non-finite value is, else the most negative one
  double mean() const { return values ? sum / double(values) : 0.0; }
};
// Reads every value of every resolution level of an image file, a band of tiles or scanlines at a time (memory
// bounded by one band, not the image): the checks a converted texture gets from read_image, for a pre-tiled .tx or
// EXR that the texture system reads as it is. Throws InputError when the file cannot be decoded.
ImageScan scan_image_values(const std::filesystem::path& file);

// One float channel named "Y" (a height, visibility or cone map: one value a texel; kozu's images are RGB), rows top
// first, zip-compressed, with string attributes; written to a temporary file renamed into place. Throws
// std::runtime_error naming the file.
void write_single_channel_exr(const std::filesystem::path& file, int width, int height,
                              const std::vector<float>& values,
                              const std::vector<std::pair<std::string, std::string>>& attributes = {});

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
  // OpenEXR compression: zip by default; "none" where the write's time matters more than 10 % of its size (noisy
  // float pixels barely compress: a 4K render is 91 MB zipped in 3 s, 100 MB raw in 0.3 s), as under --budget.
  std::string exr_compression = "zip";
};
void write_image(const std::filesystem::path& file, int width, int height, const std::vector<float>& rgb,
                 const ToneMap& tonemap, const ImageExtras& extras);

bool is_supported_output(const std::filesystem::path& file);

}  // namespace kozu
