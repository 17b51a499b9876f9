// Texture throughput and memory (docs/textures.md, "Performance").
//
//   BM_ImageLookup        lookups/s of a 2048² 8-bit sRGB PNG (converted by the TextureCache to a 16-bit tiled
//                         mip-mapped texture) with the ewa, trilinear and closest filters, at random (u, v) over
//                         the whole texture, for footprints of 0 (a point), 1, 8 and 64 texels and a 64 × 4
//                         anisotropic one (a grazing view); one thread
//   BM_CheckerLookup      the same for the procedural checkerboard (its closed-form box filter)
//   BM_TexturedRenderRatio  the time per sample of each textured albedo over the constant one, from renders of the
//                         two alternating in one loop (one thread, 2 spp each): robust to a machine's varying load
//   BM_TexturedRender     samples/s of a ground quad and a sphere under the sun and a dim sky, 320 × 240, two
//                         threads, with a constant albedo against the image texture (ewa, closest) and the checker
//   BM_TextureCacheMemory a scene's worth of large textures under a 256 MiB cache: 4 × 8192² RGB half EXR
//                         (1.5 GiB of source pixels, 3 GiB once converted to float tiles) looked up at random
//                         at full resolution; reports the cache's tile memory and the process's peak RSS
//
// Images are generated on first use under <temp>/kozu_bench_textures/ and kept between runs (the large set takes
// a few minutes to make and ~5 GB of disk; it is made by a child process, `bench_textures --make-large-textures
// DIR`, so that the generation's memory does not count in this process's peak RSS). Run the memory benchmark
// alone for a meaningful peak RSS:
//
//   build/bench/bench_textures --benchmark_filter='BM_(Image|Checker)Lookup|BM_TexturedRender'
//       --benchmark_repetitions=3 --benchmark_report_aggregates_only=true    (one command line)
//   build/bench/bench_textures --benchmark_filter=BM_TextureCacheMemory
//       --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
#include "bench_support.h"
#include "core/rng.h"
#include "integrators/path.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "textures/checker_texture.h"
#include "textures/image_texture.h"
#include "textures/texture_cache.h"

#include <OpenImageIO/imageio.h>
#include <OpenImageIO/texture.h>
#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace kozu {
namespace {

namespace fs = std::filesystem;

fs::path bench_dir() { return fs::temp_directory_path() / "kozu_bench_textures"; }

// Writes width × height × 3 channels from pixel(x, y, c) in bands of rows (a large image never sits in memory
// whole), converting to `format` on write.
template <class Pixel>
void write_image_bands(const fs::path& file, int width, int height, OIIO::TypeDesc format, const char* compression,
                       Pixel&& pixel) {
  const fs::path temp = file.string() + ".tmp" + fs::path(file).extension().string();
  auto out = OIIO::ImageOutput::create(temp.string());
  if (!out) throw std::runtime_error("cannot create " + temp.string());
  OIIO::ImageSpec spec(width, height, 3, format);
  if (compression) spec.attribute("compression", compression);
  if (!out->open(temp.string(), spec)) throw std::runtime_error(out->geterror());
  constexpr int kBand = 128;
  std::vector<float> band(static_cast<size_t>(width) * kBand * 3);
  for (int y0 = 0; y0 < height; y0 += kBand) {
    const int y1 = std::min(height, y0 + kBand);
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < width; ++x)
        for (int c = 0; c < 3; ++c) band[(static_cast<size_t>(y - y0) * width + x) * 3 + c] = pixel(x, y, c);
    if (!out->write_scanlines(y0, y1, 0, OIIO::TypeDesc::FLOAT, band.data())) throw std::runtime_error(out->geterror());
  }
  out->close();
  fs::rename(temp, file);
}

// ---- lookups ------------------------------------------------------------------------------------------

constexpr int kImageSize = 2048;

// A 2048² 8-bit PNG with detail at every scale (a colour ramp, checks of 4 and 64 texels, a hash noise).
const fs::path& lookup_image() {
  static const fs::path file = [] {
    const fs::path f = bench_dir() / "lookup_2048.png";
    if (!fs::exists(f)) {
      fs::create_directories(bench_dir());
      write_image_bands(f, kImageSize, kImageSize, OIIO::TypeDesc::UINT8, nullptr, [](int x, int y, int c) {
        const uint32_t h = (static_cast<uint32_t>(x) * 73856093u) ^ (static_cast<uint32_t>(y) * 19349663u) ^
                           (static_cast<uint32_t>(c) * 83492791u);
        const float check = (((x >> 2) ^ (y >> 2)) & 1) * 0.2f + (((x >> 6) ^ (y >> 6)) & 1) * 0.3f;
        const float ramp = c == 0 ? x / float(kImageSize) : c == 1 ? y / float(kImageSize) : 0.5f;
        return std::min(1.0f, 0.3f * ramp + check + 0.2f * float(h % 1024u) / 1024.0f);
      });
    }
    return f;
  }();
  return file;
}

TextureCache& lookup_cache() {
  static TextureCache cache(TextureCacheOptions{1024, bench_dir() / "tx"});
  return cache;
}

const char* filter_name(int64_t f) {
  static const char* names[] = {"ewa", "trilinear", "closest"};
  return names[f];
}

// Footprint cases: d(u, v)/dx and d(u, v)/dy in texels of the 2048² image.
struct Footprint {
  const char* name;
  float dx, dy;  // lengths along x and y (the axes of the ellipse), texels
};
constexpr Footprint kFootprints[] = {{"point", 0.0f, 0.0f},
                                     {"1 texel", 1.0f, 1.0f},
                                     {"8 texels", 8.0f, 8.0f},
                                     {"64 texels", 64.0f, 64.0f},
                                     {"64x4 aniso", 64.0f, 4.0f}};

// Random queries over the whole texture (a fixed set, cycled), with the footprint's axes turned at random.
std::vector<TextureQuery> make_queries(const Footprint& fp, float texels_per_unit) {
  std::vector<TextureQuery> q(1 << 16);
  Pcg32 rng(7);
  for (TextureQuery& t : q) {
    t.uv = Vec2(rng.next_float(), rng.next_float());
    const float a = kTwoPi * rng.next_float();
    const Vec2 major(std::cos(a), std::sin(a)), minor(-std::sin(a), std::cos(a));
    t.duvdx = major * (fp.dx / texels_per_unit);
    t.duvdy = minor * (fp.dy / texels_per_unit);
  }
  return q;
}

void run_lookups(benchmark::State& state, const Texture& tex, const std::vector<TextureQuery>& queries) {
  size_t i = 0;
  Rgb sum(0.0f);
  for (auto _ : state) {
    sum += tex.eval(queries[i]);
    i = (i + 1) & (queries.size() - 1);
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(state.iterations());
}

void BM_ImageLookup(benchmark::State& state) {
  ImageTexture::Options opt;
  opt.filter = static_cast<ImageTexture::Filter>(state.range(0));
  const Footprint& fp = kFootprints[state.range(1)];
  TextureCache& cache = lookup_cache();
  const ImageTexture tex(cache, cache.prepare(lookup_image(), ColorSpace::Auto, TextureUse::Color), opt);
  const auto queries = make_queries(fp, kImageSize);
  for (const TextureQuery& q : queries) benchmark::DoNotOptimize(tex.eval(q));  // tiles in memory: warm cache
  run_lookups(state, tex, queries);
  state.SetLabel(fmt::format("{}, {}", filter_name(state.range(0)), fp.name));
}
BENCHMARK(BM_ImageLookup)->ArgsProduct({{0, 1, 2}, {0, 1, 2, 3, 4}})->ArgNames({"filter", "footprint"});

void BM_CheckerLookup(benchmark::State& state) {
  // 8 × 8 checks over the unit square; footprints in the same 2048-per-unit texel units as the image's.
  const CheckerTexture tex(Vec2(8.0f), Rgb(0.8f), Rgb(0.2f));
  const Footprint& fp = kFootprints[state.range(0)];
  run_lookups(state, tex, make_queries(fp, kImageSize));
  state.SetLabel(fp.name);
}
BENCHMARK(BM_CheckerLookup)->DenseRange(0, 4)->ArgNames({"footprint"});

// ---- render ---------------------------------------------------------------------------------------------

constexpr Vec2i kRenderResolution{320, 240};

const char* albedo_case(int64_t i) {
  static const char* names[] = {"constant", "image ewa", "image closest", "checker"};
  return names[i];
}

const Scene& textured_scene(int64_t i) {
  static std::map<int64_t, std::unique_ptr<Scene>> cache;
  auto& s = cache[i];
  if (s) return *s;
  const std::string file = lookup_image().string();
  const std::string albedo[] = {
      "0.5", fmt::format(R"({{"type": "image", "file": "{}", "uv_scale": [4, 4], "filter": "ewa"}})", file),
      fmt::format(R"({{"type": "image", "file": "{}", "uv_scale": [4, 4], "filter": "closest"}})", file),
      R"({"type": "checker", "scale": [32, 32], "a": 0.8, "b": 0.2})"};
  const std::string json = fmt::format(R"({{
    "camera": {{"position": [0, 1.2, 3.5], "look_at": [0, 0.4, 0], "fov": 45}},
    "render": {{"max_depth": 4}},
    "materials": {{"ground": {{"type": "diffuse", "albedo": {0}}}, "ball": {{"type": "diffuse", "albedo": {0}}}}},
    "shapes": [{{"type": "quad", "material": "ground", "vertices": [[-4, 0, 4], [4, 0, 4], [4, 0, -4], [-4, 0, -4]]}},
               {{"type": "sphere", "center": [0, 0.5, 0], "radius": 0.5, "material": "ball"}}],
    "lights": [{{"type": "directional", "direction": [0.5, -1, -0.3], "irradiance": 3}},
               {{"type": "environment", "radiance": [0.1, 0.15, 0.25]}}] }})",
                                       albedo[i]);
  SceneLoadOptions options;
  options.textures.convert_dir = bench_dir() / "tx";
  s = load_scene_text(json, "textured.json", bench_dir(), options);
  s->camera.set_resolution(kRenderResolution);
  return *s;
}

void BM_TexturedRender(benchmark::State& state) {
  bench::measure_renders(state, textured_scene(state.range(0)), static_cast<int>(state.range(1)), 4,
                         kRenderResolution);
  state.SetLabel(albedo_case(state.range(0)));
}
BENCHMARK(BM_TexturedRender)
    ->ArgsProduct({{0, 1, 2, 3}, {2}})
    ->ArgNames({"albedo", "threads"})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

// The cost per sample of a textured albedo relative to the constant one, from renders of the two scenes
// alternating within each iteration: machine load that comes and goes hits both alike.
void BM_TexturedRenderRatio(benchmark::State& state) {
  const Scene& base = textured_scene(0);
  const Scene& textured = textured_scene(state.range(0));
  PathIntegrator base_integrator(base, base.settings.max_depth), integrator(textured, textured.settings.max_depth);
  RenderSettings opt;
  opt.spp = 2;
  opt.threads = 1;
  double base_seconds = 0, seconds = 0;
  for (auto _ : state) {
    Film a(kRenderResolution.x, kRenderResolution.y), b(kRenderResolution.x, kRenderResolution.y);
    base_seconds += render(base, base_integrator, a, opt).seconds;
    seconds += render(textured, integrator, b, opt).seconds;
  }
  state.counters["time_ratio"] = seconds / base_seconds;
  state.SetLabel(fmt::format("{} / constant", albedo_case(state.range(0))));
}
BENCHMARK(BM_TexturedRenderRatio)->DenseRange(1, 3)->ArgNames({"albedo"})->Unit(benchmark::kMillisecond)->MinTime(4.0);

// ---- memory bound ---------------------------------------------------------------------------------------

constexpr int kLargeCount = 4;
constexpr int kLargeSize = 8192;

fs::path large_dir() { return bench_dir() / fmt::format("large-{}x{}-v1", kLargeCount, kLargeSize); }
fs::path large_source(int i) { return large_dir() / fmt::format("large_{}.exr", i); }

// Child process: the sources (scanline half EXR, uncompressed) and their conversions by the TextureCache.
int make_large_textures(const fs::path& dir) {
  fs::create_directories(dir);
  TextureCache cache(TextureCacheOptions{256, dir});
  for (int i = 0; i < kLargeCount; ++i) {
    const fs::path src = dir / fmt::format("large_{}.exr", i);
    if (!fs::exists(src)) {
      std::fprintf(stderr, "bench_textures: writing %s\n", src.c_str());
      const float f = 0.001f * (i + 1);
      write_image_bands(src, kLargeSize, kLargeSize, OIIO::TypeDesc::HALF, "none", [&](int x, int y, int c) {
        return 0.5f + 0.4f * std::sin(f * x + 0.7f * c) * std::cos(f * 1.3f * y + i);
      });
    }
    std::fprintf(stderr, "bench_textures: converting %s\n", src.c_str());
    cache.prepare(src, ColorSpace::Auto, TextureUse::Color);
  }
  std::ofstream(dir / "complete") << "ok\n";
  return 0;
}

std::string self_executable() {
  char buf[4096];
  const ssize_t n = ::readlink("/proc/self/exe", buf, sizeof(buf) - 1);
  if (n <= 0) throw std::runtime_error("cannot find /proc/self/exe");
  return std::string(buf, static_cast<size_t>(n));
}

double g_rss_at_start_mb = 0;  // set in main, before any benchmark

// A counter of OpenImageIO's tile cache (int or int64, by version).
int64_t cache_statistic(const TextureCache& cache, const char* name) {
  int64_t v64 = 0;
  if (cache.system().getattribute(name, OIIO::TypeDesc::INT64, &v64)) return v64;
  int v = 0;
  return cache.system().getattribute(name, OIIO::TypeDesc::INT, &v) ? v : 0;
}

double peak_rss_mb() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss / 1024.0;  // KiB on Linux
}

double current_rss_mb() {
  long pages = 0, resident = 0;
  if (std::FILE* f = std::fopen("/proc/self/statm", "r")) {
    if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
    std::fclose(f);
  }
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

void BM_TextureCacheMemory(benchmark::State& state) {
  if (!fs::exists(large_dir() / "complete")) {
    const std::string cmd = fmt::format("'{}' --make-large-textures '{}'", self_executable(), large_dir().string());
    if (std::system(cmd.c_str()) != 0) {
      state.SkipWithError("generating the large textures failed");
      return;
    }
  }
  // Level 0 of every texture: half RGB in the sources, float RGB once converted (float sources stay float).
  const double texels = static_cast<double>(kLargeSize) * kLargeSize * kLargeCount;
  TextureCache cache(TextureCacheOptions{static_cast<int>(state.range(1)), large_dir()});
  std::vector<std::unique_ptr<ImageTexture>> textures;
  ImageTexture::Options opt;
  opt.filter = static_cast<ImageTexture::Filter>(state.range(0));
  for (int i = 0; i < kLargeCount; ++i)
    textures.push_back(std::make_unique<ImageTexture>(
        cache, cache.prepare(large_source(i), ColorSpace::Auto, TextureUse::Color), opt));
  // Random points on random textures, at full resolution (closest) or a 1-texel footprint (ewa): nearly every
  // lookup needs a tile the cache may have evicted.
  const auto queries = make_queries(Footprint{"1 texel", 1.0f, 1.0f}, kLargeSize);
  size_t i = 0;
  Rgb sum(0.0f);
  double max_cache_mb = 0;
  const int64_t tiles_before = cache_statistic(cache, "stat:tiles_created");
  for (auto _ : state) {
    sum += textures[i % kLargeCount]->eval(queries[i & (queries.size() - 1)]);
    if ((++i & 1023) == 0) max_cache_mb = std::max(max_cache_mb, cache.stats().memory_mb);
  }
  benchmark::DoNotOptimize(sum);
  const TextureCache::Stats st = cache.stats();
  const double tiles_read = static_cast<double>(cache_statistic(cache, "stat:tiles_created") - tiles_before);
  state.SetItemsProcessed(state.iterations());
  state.counters["source_MiB"] = texels * 3 * 2 / (1024.0 * 1024.0);
  state.counters["tiles_MiB"] = texels * 3 * 4 / (1024.0 * 1024.0);
  state.counters["cache_limit_MiB"] = st.memory_limit_mb;
  state.counters["cache_MiB"] = st.memory_mb;
  state.counters["cache_max_MiB"] = std::max(max_cache_mb, st.memory_mb);
  state.counters["tile_reads_per_lookup"] = tiles_read / static_cast<double>(state.iterations());
  state.counters["rss_start_MiB"] = g_rss_at_start_mb;
  state.counters["rss_MiB"] = current_rss_mb();
  state.counters["peak_rss_MiB"] = peak_rss_mb();
  state.SetLabel(filter_name(state.range(0)));
}
// The 256 MiB cases first: peak RSS is the process's, and the unbounded-looking 4096 MiB case (for contrast) raises it.
BENCHMARK(BM_TextureCacheMemory)
    ->Args({2, 256})
    ->Args({0, 256})
    ->Args({2, 4096})
    ->ArgNames({"filter", "cache_mb"})
    ->MinTime(2.0);

}  // namespace
}  // namespace kozu

int main(int argc, char** argv) {
  if (argc == 3 && std::strcmp(argv[1], "--make-large-textures") == 0) return kozu::make_large_textures(argv[2]);
  kozu::g_rss_at_start_mb = kozu::current_rss_mb();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
