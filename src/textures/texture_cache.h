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
// Memory: the cache holds at most `memory_mb` of tiles (OpenImageIO's max_memory_MB); stats() reports its use
// and hit rate for `kozu render --stats`.
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
  // no colour conversion, else its converted copy (made now, or found from an earlier run). Throws InputError
  // naming the source. Safe to call from several threads.
  std::filesystem::path prepare(const std::filesystem::path& source, ColorSpace space, TextureUse use);

  OIIO::TextureSystem& system() const { return *ts_; }

  struct Stats {
    double memory_mb = 0;  // tile memory in use
    int memory_limit_mb = 0;
    uint64_t lookups = 0;  // tile lookups
    double hit_rate = 1;   // fraction of tile queries served without reading a tile from disk, in [0, 1]
    uint64_t tiles_read = 0;  // tiles read from disk (again after an eviction)
    double mb_read = 0;       // uncompressed pixel data read from disk
    int files = 0;         // texture files opened
    int converted = 0;     // sources converted in this run
    int reused = 0;        // conversions found from an earlier run
  };
  Stats stats() const;

 private:
  OIIO::TextureSystem* ts_;
  TextureCacheOptions options_;
  mutable std::mutex mutex_;  // guards the counters
  int converted_ = 0, reused_ = 0;
};

// Converts source into a tiled mip-mapped texture at output (`kozu maketx`), with the conversion rules above.
void make_tiled_texture(const std::filesystem::path& source, const std::filesystem::path& output, ColorSpace space,
                        TextureUse use);

}  // namespace kozu
