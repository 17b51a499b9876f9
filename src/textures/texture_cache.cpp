#include "textures/texture_cache.h"

#include "core/error.h"
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
constexpr int kConversionVersion = 1;

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

}  // namespace

void make_tiled_texture(const std::filesystem::path& source, const std::filesystem::path& output, ColorSpace space,
                        TextureUse use) {
  Image img = read_image(source);  // size, memory and NaN checks
  const bool srgb = decodes_srgb(space, use, img.source_is_float);
  if (srgb) {
    const size_t colour = static_cast<size_t>(std::min(img.channels, 3));  // alpha stays linear
    for (size_t i = 0; i < img.data.size(); ++i)
      if (i % static_cast<size_t>(img.channels) < colour) img.data[i] = srgb_to_linear(img.data[i]);
  }
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
  static std::atomic<int> counter{0};
  const std::filesystem::path temp =
      output.string() + fmt::format(".tmp-{}-{}.tx", static_cast<long>(getpid()), counter++);
  std::ostringstream log;
  if (!OIIO::ImageBufAlgo::make_texture(OIIO::ImageBufAlgo::MakeTxTexture, buf, temp.string(), config, &log)) {
    std::filesystem::remove(temp, ec);
    throw InputError(source.string(), "",
                     fmt::format("cannot write the texture {}: {}", output.string(), text_of(OIIO::geterror())));
  }
  std::filesystem::rename(temp, output, ec);
  if (ec) {
    std::filesystem::remove(temp, ec);
    throw InputError(source.string(), "",
                     fmt::format("cannot write the texture {}: {}", output.string(), ec.message()));
  }
}

TextureCache::TextureCache(const TextureCacheOptions& options)
    : ts_(system_pool().acquire()), options_(options) {
  ts_->attribute("max_memory_MB", static_cast<float>(options.memory_mb));
  ts_->attribute("autotile", 64);  // untiled sources (never passed by prepare) would otherwise load whole
  ts_->attribute("gray_to_rgb", 1);
}

TextureCache::~TextureCache() { system_pool().release(ts_); }

std::filesystem::path TextureCache::prepare(const std::filesystem::path& source, ColorSpace space, TextureUse use) {
  const ImageInfo info = probe_image(source);
  const bool srgb = decodes_srgb(space, use, info.is_float);
  if (info.tiled && info.mip_levels > 1 && !srgb) return source;

  std::error_code ec;
  const std::filesystem::path absolute = std::filesystem::absolute(source, ec);
  const auto size = std::filesystem::file_size(source, ec);
  const auto mtime = std::filesystem::last_write_time(source, ec).time_since_epoch().count();
  const size_t key = std::hash<std::string>{}(
      fmt::format("{}|{}|{}|{}|{}", absolute.string(), size, static_cast<long long>(mtime), srgb, kConversionVersion));
  const std::filesystem::path dir =
      options_.convert_dir.empty() ? std::filesystem::temp_directory_path() / "kozu-tx" : options_.convert_dir;
  const std::filesystem::path out = dir / fmt::format("{}-{:016x}.tx", source.stem().string(), key);
  if (std::filesystem::is_regular_file(out, ec) && std::filesystem::file_size(out, ec) > 0) {
    std::lock_guard lock(mutex_);
    ++reused_;
    return out;
  }
  make_tiled_texture(source, out, srgb ? ColorSpace::Srgb : ColorSpace::Linear, use);
  std::lock_guard lock(mutex_);
  ++converted_;
  return out;
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
  s.hit_rate =
      find_calls > 0 ? std::clamp(1.0 - static_cast<double>(tiles_created) / static_cast<double>(find_calls), 0.0, 1.0)
                     : 1.0;
  s.files = static_cast<int>(statistic(*ts_, "stat:unique_files"));
  std::lock_guard lock(mutex_);
  s.converted = converted_;
  s.reused = reused_;
  return s;
}

}  // namespace kozu
