#include "textures/texture_cache.h"

#include "core/error.h"
#include "core/file_io.h"
#include "core/memory.h"
#include "core/temp_files.h"
#include "io/image_io.h"

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/texture.h>
#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <functional>
#include <sstream>
#include <vector>

namespace kozu {

namespace {

// Bumped when the conversion changes, so that old cache files are not reused.
constexpr int kConversionVersion = 2;  // 2: tiny negative colour values clamped, others refused

bool decodes_srgb(ColorSpace space, TextureUse use, bool is_float) {
  if (space != ColorSpace::Auto) return space == ColorSpace::Srgb;
  return use == TextureUse::Color && !is_float;
}

// An ImageCache statistic, whichever integer type this OpenImageIO version reports it in; 0 if unknown.
int64_t statistic(const OIIO::TextureSystem& ts, const char* name) {
  int64_t v64 = 0;
  if (ts.getattribute(name, OIIO::TypeDesc::INT64, &v64)) return v64;
  int v = 0;
  if (ts.getattribute(name, OIIO::TypeDesc::INT, &v)) return v;
  return 0;
}

// TextureSystems are kept for the life of the process and handed from one TextureCache to the next:
// OpenImageIO 2.4's TextureSystem::destroy deletes its object with a size that differs from the one create
// allocated (AddressSanitizer: new-delete-type-mismatch inside libOpenImageIO), so kozu never calls it. A pooled
// system is emptied (invalidate_all, reset_stats) before it is lent again; at most as many exist as caches ever
// lived at once (one per render).
class SystemPool {
 public:
  OIIO::TextureSystem* acquire() {
    {
      std::lock_guard lock(mutex_);
      if (!free_.empty()) {
        OIIO::TextureSystem* ts = free_.back();
        free_.pop_back();
        return ts;
      }
    }
    return OIIO::TextureSystem::create(/*shared=*/false);
  }
  void release(OIIO::TextureSystem* ts) {
    ts->invalidate_all(/*force=*/true);
    ts->reset_stats();
    std::lock_guard lock(mutex_);
    free_.push_back(ts);
  }

 private:
  std::mutex mutex_;
  std::vector<OIIO::TextureSystem*> free_;
};

SystemPool& system_pool() {
  static auto* pool = new SystemPool;  // never destroyed: texture caches may outlive static destruction order
  return *pool;
}

std::string text_of(const std::string& s) {
  std::string t = s;
  while (!t.empty() && (t.back() == '\n' || t.back() == ' ')) t.pop_back();
  return t;
}

// The reason a texture could not be written, in one line: OpenImageIO's error is libtiff's or OpenEXR's report of
// every tile that failed (82 lines for a full disk), so its first line is kept, and a full disk is named.
std::string write_failure(const std::filesystem::path& output, uint64_t bytes) {
  const std::string all = OIIO::geterror();  // also clears it
  std::string why = text_of(all.substr(0, all.find('\n')));
  if (why.size() > 200) why = why.substr(0, 200) + "...";
  if (why.empty()) why = "unknown error";
  std::error_code ec;
  const std::filesystem::space_info space =
      std::filesystem::space(output.has_parent_path() ? output.parent_path() : std::filesystem::path("."), ec);
  if (!ec && space.available < bytes)
    why += fmt::format(" (no space left on device: {} free)", format_bytes(double(space.available)));
  return why;
}

}  // namespace

uint64_t make_tiled_texture_bytes(int width, int height, int channels) {
  // Measured (kozu maketx, OpenImageIO 2.4, 4096^2): peak RSS 1.78 times the image's float bytes B for float RGBA
  // (478 MB), 1.95 B for 8-bit RGB converted to 16 bits (391 MB), the process's own 25 MB included: the float image,
  // the last step of its read (the buffer grows), the mip levels (B / 3) and the converted tiles. 2 B + 64 MiB
  // bounds both.
  const uint64_t floats = uint64_t(width) * uint64_t(height) * uint64_t(std::min(channels, 4));
  return 2 * floats * sizeof(float) + (uint64_t{64} << 20);
}

uint64_t max_tile_bytes(int memory_mb) {
  return std::min<uint64_t>((uint64_t(std::max(memory_mb, 1)) << 20) / 16, uint64_t{16} << 20);
}

uint64_t make_tiled_texture(const std::filesystem::path& source, const std::filesystem::path& output, ColorSpace space,
                            TextureUse use) {
  // The memory the conversion needs, from the header, before a pixel is read.
  const ImageInfo info = probe_image(source);
  const uint64_t need = make_tiled_texture_bytes(info.width, info.height, info.channels);
  const MemoryLimit limit = memory_limit();
  if (static_cast<double>(need) > memory_left(limit))
    throw InputError(source.string(), "",
                     fmt::format("converting this {} x {} image into a texture needs about {}, more than is left of "
                                 "the {} memory limit ({})",
                                 info.width, info.height, format_bytes(double(need)), format_bytes(double(limit.bytes)),
                                 limit.source));
  Image img = read_image(source);  // size, memory and NaN checks
  const bool srgb = decodes_srgb(space, use, img.source_is_float);
  if (srgb) {
    const size_t colour = static_cast<size_t>(std::min(img.channels, 3));  // alpha stays linear
    for (size_t i = 0; i < img.data.size(); ++i)
      if (i % static_cast<size_t>(img.channels) < colour) img.data[i] = srgb_to_linear(img.data[i]);
  }
  // Colours are >= 0 (data, such as a float normal or displacement map, may be negative): tiny negative values are
  // filtering noise, clamped; others are refused.
  const uint64_t clamped = use == TextureUse::Color ? clamp_small_negatives(img, source, 0, "a colour") : 0;
  const OIIO::ImageSpec spec(img.width, img.height, img.channels, OIIO::TypeDesc::FLOAT);
  const OIIO::ImageBuf buf(spec, img.data.data());
  OIIO::ImageSpec config;
  // Decoded sRGB needs more than 8 bits of linear precision: 16-bit integers hold every 8-bit sRGB step (the
  // smallest, 1/255 / 12.92, is 20 of them) and TIFF stores them natively (not half floats). Float sources keep
  // float: radiance exceeds half's range.
  if (img.source_is_float)
    config.format = OIIO::TypeDesc::FLOAT;
  else if (srgb)
    config.format = OIIO::TypeDesc::UINT16;
  else
    config.format = img.source_bits <= 8 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::UINT16;
  config.tile_width = config.tile_height = 64;
  config.attribute("compression", "zip");
  config.attribute("maketx:filtername", "box");  // each level the mean of the one above: no ringing
  std::error_code ec;
  if (output.has_parent_path()) std::filesystem::create_directories(output.parent_path(), ec);
  // Beside the output (an atomic rename), hidden, unique in the process (two threads may convert one source), with
  // the output's extension (the writer is chosen by it); registered, so a signal or an error never leaves it.
  static std::atomic<int> counter{0};
  TempFileGuard temp(output.parent_path() / fmt::format(".{}.{}-{}.tmp{}", output.stem().string(),
                                                        static_cast<long>(getpid()), counter++,
                                                        output.extension().string()));
  std::ostringstream log;
  if (!OIIO::ImageBufAlgo::make_texture(OIIO::ImageBufAlgo::MakeTxTexture, buf, temp.path().string(), config, &log))
    throw InputError(source.string(), "",
                     fmt::format("cannot write the texture {}: {}", output.string(),
                                 write_failure(output, img.data.size() * (img.source_is_float ? 4 : 2))));
  try {
    rename_into_place(temp, output);
  } catch (const std::runtime_error& e) {
    throw InputError(source.string(), "", fmt::format("cannot write the texture {}", e.what()));
  }
  return clamped;
}

TextureCache::TextureCache(const TextureCacheOptions& options) : ts_(system_pool().acquire()), options_(options) {
  ts_->attribute("max_memory_MB", static_cast<float>(options.memory_mb));
  ts_->attribute("autotile", 64);  // untiled sources (never passed by prepare) would otherwise load whole
  ts_->attribute("gray_to_rgb", 1);
}

TextureCache::~TextureCache() { system_pool().release(ts_); }

std::filesystem::path TextureCache::prepare(const std::filesystem::path& source, ColorSpace space, TextureUse use,
                                            std::string* warning) {
  const ImageInfo info = probe_image(source);
  const bool srgb = decodes_srgb(space, use, info.is_float);
  const auto clamped_warning = [&](uint64_t clamped) {
    if (warning && clamped > 0)
      *warning = fmt::format("{}: {} tiny negative value{} (filtering noise) clamped to 0", source.string(), clamped,
                             clamped == 1 ? "" : "s");
  };

  std::error_code ec;
  const std::filesystem::path absolute = std::filesystem::absolute(source, ec);
  const auto size = std::filesystem::file_size(source, ec);
  const auto mtime = std::filesystem::last_write_time(source, ec).time_since_epoch().count();
  const auto cached = [&](bool decode, const char* suffix) {
    const size_t key = std::hash<std::string>{}(fmt::format("{}|{}|{}|{}|{}", absolute.string(), size,
                                                            static_cast<long long>(mtime), decode, kConversionVersion));
    return convert_folder() / fmt::format("{}-{:016x}{}", source.stem().string(), key, suffix);
  };

  // A pre-tiled file is read as it is when its tiles fit the cache and its values pass the checks a converted
  // image gets (its scan is remembered by a marker file while the file is unchanged).
  if (info.tiled && info.mip_levels > 1 && !srgb &&
      uint64_t(info.tile_width) * uint64_t(info.tile_height) * uint64_t(std::min(info.channels, 4)) * sizeof(float) <=
          max_tile_bytes(options_.memory_mb)) {
    const std::filesystem::path marker = cached(false, ".checked");
    if (std::filesystem::is_regular_file(marker, ec)) return source;
    std::filesystem::create_directories(marker.parent_path(), ec);
    const ImageScan scan = scan_image_values(source);
    if (scan.nonfinite > 0)
      throw InputError(
          source.string(), "",
          fmt::format("{} NaN or infinite value{} (the first at pixel ({}, {}) channel {} of resolution "
                      "level {}); a texture's values must be finite",
                      scan.nonfinite, scan.nonfinite == 1 ? "" : "s", scan.x, scan.y, scan.channel, scan.level));
    const bool negatives = use == TextureUse::Color && scan.negative > 0;
    if (negatives && !scan.negatives.noise())
      throw InputError(source.string(), "",
                       fmt::format("a colour must be >= 0, and pixel ({}, {}) channel {} is {:g}: {}", scan.x, scan.y,
                                   scan.channel, scan.most_negative, scan.negatives.why_not_noise()));
    if (!negatives) {
      if (scan.negative == 0) {
        try {
          write_file_atomic(marker, "");  // a later run skips the scan
        } catch (const std::exception&) {
          // Only a saving: the next run scans again.
        }
      }
      return source;
    }
    // Tiny negative colour values: converted below, where they are clamped.
  }

  // The count of values a conversion clamped is kept beside it (`<name>-<key>.tx.clamped`), so that a run reusing
  // it warns too.
  const std::filesystem::path out = cached(srgb, ".tx");
  const std::filesystem::path clamped_file = out.string() + ".clamped";
  if (std::filesystem::is_regular_file(out, ec) && std::filesystem::file_size(out, ec) > 0) {
    if (std::filesystem::is_regular_file(clamped_file, ec)) {
      try {
        clamped_warning(std::stoull(read_input_file(clamped_file, 64)));
      } catch (const std::exception&) {
        // A damaged note only loses the warning.
      }
    }
    std::lock_guard lock(mutex_);
    ++reused_;
    return out;
  }
  const uint64_t clamped = make_tiled_texture(source, out, srgb ? ColorSpace::Srgb : ColorSpace::Linear, use);
  if (clamped > 0) {
    try {
      write_file_atomic(clamped_file, std::to_string(clamped));
    } catch (const std::exception&) {
      // Only a later run's warning is lost.
    }
  }
  clamped_warning(clamped);
  std::lock_guard lock(mutex_);
  ++converted_;
  return out;
}

std::filesystem::path TextureCache::convert_folder(const TextureCacheOptions& options) {
  return options.convert_dir.empty() ? std::filesystem::temp_directory_path() / "kozu-tx" : options.convert_dir;
}

TextureCache::Stats TextureCache::stats() const {
  Stats s;
  const int64_t memory = statistic(*ts_, "stat:cache_memory_used");
  const int64_t find_calls = statistic(*ts_, "stat:find_tile_calls");
  const int64_t tiles_created = statistic(*ts_, "stat:tiles_created");
  s.memory_mb = static_cast<double>(memory) / (1024.0 * 1024.0);
  s.memory_limit_mb = options_.memory_mb;
  s.lookups = static_cast<uint64_t>(std::max<int64_t>(find_calls, 0));
  s.tiles_read = static_cast<uint64_t>(std::max<int64_t>(tiles_created, 0));
  s.mb_read = static_cast<double>(std::max<int64_t>(statistic(*ts_, "stat:bytes_read"), 0)) / (1024.0 * 1024.0);
  // A tile query can read more than one tile once tiles are evicted and re-read (measured: 1.47 reads per query
  // with a 256 MB cache over 3 GB of tiles), so the ratio is clamped: 0 means "every query read from disk".
  s.hit_rate = find_calls > 0
                   ? std::clamp(1.0 - static_cast<double>(tiles_created) / static_cast<double>(find_calls), 0.0, 1.0)
                   : 1.0;
  s.files = static_cast<int>(statistic(*ts_, "stat:unique_files"));
  std::lock_guard lock(mutex_);
  s.converted = converted_;
  s.reused = reused_;
  return s;
}

}  // namespace kozu
