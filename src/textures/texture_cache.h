// The texture cache: OpenImageIO's TextureSystem (tiled, mip-mapped, cached, thread-safe lookups) and the
// conversion of ordinary images into the tiled mip-mapped textures it reads.
//
// Conversion: an image that is not already a tiled mip-mapped texture in the colour space kozu shades in is read
// with read_image's checks (io/image_io.h), linearized when it is sRGB-encoded, and written once by
// ImageBufAlgo::make_texture to `<cache folder>/<name>-<key>.tx`, where the key hashes the source's absolute path,
// size, modification time and colour space: a later run reuses the file while the source is unchanged. sRGB
// images become 16-bit linear textures (8 bits of linear values would band in the shadows); data images keep
// their format, float images stay float. The file is written beside its final name and renamed into place, so
// concurrent renders sharing a cache folder never read a partial texture.
//
// Colour spaces: "srgb" (decoded with the sRGB transfer function, IEC 61966-2-1), "linear" (used as stored), or
// "auto": sRGB for 8- and 16-bit integer images that hold colours, linear for floating-point images and for data
// (roughness, normals, metallic, opacity).
//
// Pre-tiled files (a .tx, a tiled mip-mapped EXR or TIFF) are read as they are, after a scan of every value of every
// resolution level, a band of tiles at a time (scan_image_values, io/image_io.h): NaN or infinite values are
// refused as in a converted image, and so are meaningfully negative colour values; tiny negative ones (filtering
// noise, NegativeValues in io/image_io.h) are clamped in a converted copy, with one warning. A clean file is remembered
// in the cache folder (`<name>-<key>.checked`) so that later runs skip the scan while it is unchanged. A file whose
// tiles take more than 1/16 of the cache (or 16 MiB) is converted like an untiled one, into 64 x 64 tiles:
// OpenImageIO's cache cannot hold tiles near its own size (it aborts on an assertion).
//
// Memory: the cache holds at most `memory_mb` of tiles (OpenImageIO's max_memory_MB); stats() reports its use
// and hit rate for `kozu render --stats`. A conversion holds the image in float, its mip levels and the tiles being
// written: make_tiled_texture_bytes estimates it and the conversion is refused before reading when it is more than
// the memory left.
#pragma once

#include "core/color.h"

#include <OpenImageIO/oiioversion.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <string>

OIIO_NAMESPACE_BEGIN
class TextureSystem;
OIIO_NAMESPACE_END

namespace kozu {

enum class ColorSpace { Auto, Srgb, Linear };
// What a texture holds: colours ("auto" decodes 8-bit ones as sRGB) or data (always linear).
enum class TextureUse { Color, Data };

struct TextureCacheOptions {
  int memory_mb = 1024;               // --texture-cache-mb
  std::filesystem::path convert_dir;  // where converted textures are kept; empty: a "kozu-tx" folder in the temp dir
};

class TextureCache {
 public:
  explicit TextureCache(const TextureCacheOptions& options = {});
  ~TextureCache();
  TextureCache(const TextureCache&) = delete;
  TextureCache& operator=(const TextureCache&) = delete;

  // The file the TextureSystem reads for source: the source itself when it is a tiled mip-mapped texture needing
  // no colour conversion and holding tiles of at most max_tile_bytes, else its converted copy (made now, or found
  // from an earlier run). Throws InputError naming the source. Safe to call from several threads. `warning`, when
  // given, receives a message for the user (tiny negative values clamped to 0), or is left empty.
  std::filesystem::path prepare(const std::filesystem::path& source, ColorSpace space, TextureUse use,
                                std::string* warning = nullptr);

  OIIO::TextureSystem& system() const { return *ts_; }
  // The folder conversions are kept in (TextureCacheOptions::convert_dir, or its default); also the normal and gloss
  // chains of materials/normal_gloss_filtering.h.
  std::filesystem::path convert_folder() const { return convert_folder(options_); }
  static std::filesystem::path convert_folder(const TextureCacheOptions& options);

  struct Stats {
    double memory_mb = 0;  // tile memory in use
    int memory_limit_mb = 0;
    uint64_t lookups = 0;     // tile lookups
    double hit_rate = 1;      // fraction of tile queries served without reading a tile from disk, in [0, 1]
    uint64_t tiles_read = 0;  // tiles read from disk (again after an eviction)
    double mb_read = 0;       // uncompressed pixel data read from disk
    int files = 0;            // texture files opened
    int converted = 0;        // sources converted in this run
    int reused = 0;           // conversions found from an earlier run
  };
  Stats stats() const;

 private:
  OIIO::TextureSystem* ts_;
  TextureCacheOptions options_;
  mutable std::mutex mutex_;  // guards the counters
  int converted_ = 0, reused_ = 0;
};

// Converts source into a tiled mip-mapped texture at output (`kozu maketx`), with the conversion rules above.
// Returns how many tiny negative colour values were clamped to 0. Throws InputError naming the source.
uint64_t make_tiled_texture(const std::filesystem::path& source, const std::filesystem::path& output, ColorSpace space,
                            TextureUse use);
// The memory make_tiled_texture needs for an image of width x height x channels (at most 4 are read), in bytes.
uint64_t make_tiled_texture_bytes(int width, int height, int channels);
// The largest tile, in bytes of float values, that TextureCache reads as it is with a cache of memory_mb.
uint64_t max_tile_bytes(int memory_mb);

}  // namespace kozu
