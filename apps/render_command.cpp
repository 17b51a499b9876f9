// `kozu render`: load a scene, render it progressively, write images and statistics.
#include "apps/commands.h"
#include "apps/stop_signals.h"
#include "render/output_paths.h"
#ifdef KOZU_HAVE_MPI
#include "apps/mpi_world.h"
#endif
#include "core/error.h"
#include "core/file_io.h"
#include "core/memory.h"
#include "core/process_clock.h"
#include "core/version.h"
#include "integrators/path.h"
#include "io/checkpoint_file.h"
#include "io/image_io.h"
#include "media/medium.h"
#include "render/aov.h"
#include "render/checkpoint.h"
#include "render/denoiser.h"
#include "render/emission_refine.h"
#include "render/renderer.h"
#include "scene/render_settings.h"
#include "scene/scene_loader.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <thread>

namespace kozu::app {

namespace {

struct RenderArgs {
  std::string scene;
  bool demo = false;
  std::vector<std::string> outputs;
  // Numeric flags are kept as text and validated by the rules their scene keys use (scene/render_settings.h).
  std::optional<std::string> spp, time_limit, threads, seed, resolution, max_depth, exposure, texture_cache_mb;
  std::string stats;
  bool quiet = false;
  std::string tonemap = "aces";
  std::optional<std::string> direct;
  // Production (docs/production.md).
  std::optional<std::string> budget, partial_every, checkpoint_every, crop, sample_range, aov, frames;
  std::string checkpoint, resume;
  bool denoise = false, denoise_only = false;
  bool alpha = false;                    // --alpha: an A channel in the EXRs
  std::vector<std::string> defines;      // -D PATH=VALUE
  std::vector<std::string> empty_flags;  // file flags given an empty name (--stats ''), refused
};

// The flags, validated.
struct RenderFlags {
  std::optional<int> spp, max_depth;
  std::optional<double> time_limit;
  int threads = 0;
  std::optional<uint64_t> seed;
  std::optional<Vec2i> resolution;
  int texture_cache_mb = 1024;
  ToneMap tonemap;
  std::optional<DirectLighting> direct;
  std::optional<double> budget, partial_every, checkpoint_every;
  std::optional<Vec2i> sample_range;
  std::vector<Aov> aovs;
  std::vector<SceneOverride> overrides;
};

RenderFlags validate_flags(const RenderArgs& args) {
  RenderFlags f;
  if (args.spp) f.spp = static_cast<int>(integer_flag(*args.spp, setting::kSpp));
  if (args.max_depth) f.max_depth = static_cast<int>(integer_flag(*args.max_depth, setting::kMaxDepth));
  if (args.time_limit) f.time_limit = number_flag(*args.time_limit, setting::kTimeLimit);
  if (args.threads) f.threads = static_cast<int>(integer_flag(*args.threads, setting::kThreads));
  if (args.seed) f.seed = seed_flag(*args.seed);
  if (args.resolution) f.resolution = resolution_flag(*args.resolution);
  if (args.texture_cache_mb)
    f.texture_cache_mb = static_cast<int>(integer_flag(*args.texture_cache_mb, setting::kTextureCacheMb));
  try {
    f.tonemap.curve = ToneMap::parse(args.tonemap);
  } catch (const std::invalid_argument& e) {
    throw InputError("kozu render", "--tonemap", e.what());
  }
  if (args.direct) {
    try {
      f.direct = parse_direct_lighting(*args.direct);
    } catch (const std::invalid_argument& e) {
      throw InputError("kozu render", "--direct", e.what());
    }
  }
  if (args.exposure) f.tonemap.exposure = static_cast<float>(number_flag(*args.exposure, setting::kExposure));
  if (args.budget) f.budget = number_flag(*args.budget, setting::kBudget);
  if (args.partial_every) f.partial_every = number_flag(*args.partial_every, setting::kPartialEvery);
  if (args.checkpoint_every) f.checkpoint_every = number_flag(*args.checkpoint_every, setting::kCheckpointEvery);
  if (f.checkpoint_every && args.checkpoint.empty())
    throw InputError("kozu render", "--checkpoint-every", "needs --checkpoint FILE (where to write it)");
  if (args.aov) {
    try {
      f.aovs = parse_aovs(*args.aov);
    } catch (const std::invalid_argument& e) {
      throw InputError("kozu render", "--aov", e.what());
    }
  }
  if (args.sample_range) {
    f.sample_range = sample_range_flag(*args.sample_range);
    if (f.spp) throw InputError("kozu render", "--sample-range", "sets the samples itself: give it or --spp, not both");
  }
  for (const std::string& d : args.defines) {
    try {
      f.overrides.push_back(parse_scene_override(d));
    } catch (const std::invalid_argument& e) {
      throw InputError("kozu render", "", e.what());
    }
  }
  return f;
}

// Bytes a w × h render allocates (an estimate with margin): the film, and for writing the linear RGB floats,
// the writer's copy of them, the hole-filling pyramid (4/3 × 16 bytes) and the 8-bit RGB.
struct RenderMemory {
  double film = 0, buffers = 0;
  double total() const { return film + buffers; }
};
// AOVs add the feature sums and, for the EXR, their channels twice (the values and the interleaved copy).
RenderMemory render_memory(Vec2i res, bool aovs) {
  const double pixels = static_cast<double>(res.x) * res.y;
  return {pixels * static_cast<double>(Film::bytes_per_pixel() + (aovs ? sizeof(Film::FeaturePixel) : 0)),
          pixels * (12.0 + 12.0 + 22.0 + 3.0 + (aovs ? 2.0 * 4.0 * 17.0 : 0.0))};
}

std::string format_duration(double s) {
  if (!std::isfinite(s) || s < 0) return "--:--";
  const long t = static_cast<long>(s + 0.5);
  if (t >= 3600) return fmt::format("{}:{:02}:{:02}", t / 3600, (t / 60) % 60, t % 60);
  return fmt::format("{:02}:{:02}", t / 60, t % 60);
}

std::string format_rate(double per_second) {
  if (per_second >= 1e9) return fmt::format("{:.2f} G", per_second / 1e9);
  if (per_second >= 1e6) return fmt::format("{:.2f} M", per_second / 1e6);
  if (per_second >= 1e3) return fmt::format("{:.2f} k", per_second / 1e3);
  return fmt::format("{:.0f} ", per_second);
}

// Draws a progress bar on stderr until stopped.
class ProgressBar {
 public:
  ProgressBar(const RenderProgress& progress, uint64_t total_samples, double time_limit)
      : progress_(progress), total_(total_samples), time_limit_(time_limit), start_(Clock::now()) {
    thread_ = std::thread([this] { run(); });
  }
  ~ProgressBar() { stop(); }
  void stop() {
    {
      std::lock_guard lock(mutex_);
      if (done_) return;
      done_ = true;
    }
    cv_.notify_all();
    thread_.join();
    draw();
    std::fputc('\n', stderr);
  }

 private:
  using Clock = std::chrono::steady_clock;
  void run() {
    std::unique_lock lock(mutex_);
    while (!cv_.wait_for(lock, std::chrono::milliseconds(250), [this] { return done_; })) draw();
  }
  void draw() {
    const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
    const uint64_t done = progress_.samples_done.load();
    double fraction = total_ ? static_cast<double>(done) / total_ : 0.0;
    if (time_limit_ > 0) fraction = std::max(fraction, elapsed / time_limit_);
    fraction = std::min(fraction, 1.0);
    const double eta = fraction > 0 ? elapsed * (1.0 - fraction) / fraction : NAN;
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(fraction * kWidth);
    std::string bar(static_cast<size_t>(filled), '#');
    bar.append(static_cast<size_t>(kWidth - filled), '-');
    std::fprintf(stderr, "\r[%s] %5.1f%%  %ssamples/s  elapsed %s  ETA %s   ", bar.c_str(), 100.0 * fraction,
                 format_rate(elapsed > 0 ? done / elapsed : 0).c_str(), format_duration(elapsed).c_str(),
                 format_duration(eta).c_str());
    std::fflush(stderr);
  }

  const RenderProgress& progress_;
  uint64_t total_;
  double time_limit_;
  Clock::time_point start_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool done_ = false;
  std::thread thread_;
};

// Frame-number patterns in output names: "%d" or "%0Nd" (printf's), e.g. out/%04d.png.
std::optional<std::pair<size_t, size_t>> find_frame_pattern(const std::string& s) {
  for (size_t i = s.find('%'); i != std::string::npos; i = s.find('%', i + 1)) {
    size_t j = i + 1;
    while (j < s.size() && std::isdigit(static_cast<unsigned char>(s[j]))) ++j;
    if (j < s.size() && s[j] == 'd' && j - i <= 4) return std::pair{i, j + 1};
  }
  return std::nullopt;
}
bool has_frame_pattern(const std::string& s) { return find_frame_pattern(s).has_value(); }
std::string frame_path(const std::string& s, int frame) {
  const auto p = find_frame_pattern(s);
  if (!p) return s;
  const std::string spec = s.substr(p->first + 1, p->second - p->first - 2);  // "04" of "%04d"
  const int width = spec.empty() ? 0 : std::stoi(spec);
  std::string number = std::to_string(frame);
  if (static_cast<int>(number.size()) < width) number.insert(0, static_cast<size_t>(width) - number.size(), '0');
  return s.substr(0, p->first) + number + s.substr(p->second);
}

// What is already under the names a numbered output takes for frames A..B: a folder, a FIFO, a device or an input of
// the render is refused, naming the frame. A pattern in the file name reads its folder once (a million frames cost
// one listing, not a million look-ups); a pattern in a folder's name looks each frame up.
void check_numbered_output(const OutputFile& o, Vec2i frames, const std::vector<std::filesystem::path>& inputs) {
  const std::string pattern = o.path.string();
  const auto p = find_frame_pattern(pattern);
  if (!p) return;
  const auto check = [&](const std::filesystem::path& path, int f) {
    std::error_code ec;
    const auto st = std::filesystem::status(path, ec);
    if (!std::filesystem::exists(st)) return;
    if (!std::filesystem::is_regular_file(st))
      throw std::runtime_error(fmt::format("{} {}: {} (frame {}); an output must be a regular file or not exist",
                                           o.flag, path.string(),
                                           std::filesystem::is_directory(st) ? "is a folder" : "is not a file", f));
    for (const auto& in : inputs)
      if (std::filesystem::equivalent(path, in, ec))
        throw std::runtime_error(fmt::format("{} {}: would overwrite {}, an input of the render (frame {})", o.flag,
                                             path.string(), in.string(), f));
  };
  const size_t slash = pattern.find_last_of('/');
  if (slash != std::string::npos && slash > p->first) {
    for (int f = frames.x; f <= frames.y; ++f) check(frame_path(pattern, f), f);
    return;
  }
  const std::string name = slash == std::string::npos ? pattern : pattern.substr(slash + 1);
  const size_t at = p->first - (slash == std::string::npos ? 0 : slash + 1);
  const std::string prefix = name.substr(0, at), suffix = name.substr(at + (p->second - p->first));
  std::filesystem::path dir = o.path.parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string entry = it->path().filename().string();
    if (entry.size() <= prefix.size() + suffix.size() || entry.compare(0, prefix.size(), prefix) != 0 ||
        entry.compare(entry.size() - suffix.size(), suffix.size(), suffix) != 0)
      continue;
    const std::string digits = entry.substr(prefix.size(), entry.size() - prefix.size() - suffix.size());
    if (digits.size() > 9 || !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
      continue;
    const int f = std::stoi(digits);
    if (f >= frames.x && f <= frames.y && std::filesystem::path(frame_path(pattern, f)).filename() == entry)
      check(it->path(), f);
  }
}

// "--frames A:B" (both included) or "--frames N" of an animation of `count` frames.
Vec2i frames_flag(const std::string& text, int count) {
  const auto fail = [&] {
    throw InputError("kozu render", "--frames",
                     fmt::format("expected A:B (frames A to B, both included) or N with 0 <= A <= B <= {} (the scene's "
                                 "animation has {} frames), got '{}'",
                                 count - 1, count, text_excerpt(text)));
  };
  const size_t colon = text.find(':');
  Vec2i r;
  try {
    const auto number = [&](const std::string& t) {
      return static_cast<int>(
          json_to_integer(flag_value(t), "--frames", JsonSource{"kozu render"}, Range::closed(0, count - 1)));
    };
    r.x = number(text.substr(0, colon));
    r.y = colon == std::string::npos ? r.x : number(text.substr(colon + 1));
  } catch (const InputError&) {
    fail();
  }
  if (r.x > r.y) fail();
  return r;
}

// This process's place among the MPI ranks (one of one without MPI).
struct Ranks {
  int rank = 0, size = 1;
  bool distributed() const { return size > 1; }
};
Ranks mpi_ranks() {
#ifdef KOZU_HAVE_MPI
  if (const MpiWorld* w = MpiWorld::instance()) return {w->rank(), w->size()};
#endif
  return {};
}

// Errors name the rank under MPI: every rank loads and checks for itself.
void print_error(const std::string& message) {
  const Ranks ranks = mpi_ranks();
  if (ranks.distributed())
    std::fprintf(stderr, "error: rank %d: %s\n", ranks.rank, message.c_str());
  else
    std::fprintf(stderr, "error: %s\n", message.c_str());
}

// Under MPI the ranks pass together every point before which one of them could fail alone (apps/mpi_world.h): a
// rank that returns early with an error still takes part (from the destructor), so the others stop with it
// instead of waiting for it in the film's reduction, and ranks started with different settings are caught before
// they render. Without MPI it does nothing.
class RankGate {
 public:
  explicit RankGate(std::string what) : what_(std::move(what)) {}
  ~RankGate() {
    if (!passed_) pass(1, 0);
  }
  RankGate(const RankGate&) = delete;
  RankGate& operator=(const RankGate&) = delete;
  // True when every rank is ready with the same fingerprint; otherwise rank 0 names the rank that is not.
  bool pass(int status, uint64_t fingerprint) {
    passed_ = true;
#ifdef KOZU_HAVE_MPI
    const MpiWorld* world = MpiWorld::instance();
    if (!world || !world->distributed()) return status == 0;
    const MpiWorld::Agreement a = world->agree(status, fingerprint);
    if (a.ok()) return true;
    if (world->rank() == 0 && status == 0) {
      if (a.status != 0)
        std::fprintf(stderr, "error: kozu render: rank %d failed %s (its message above); every rank stopped\n",
                     a.failed_rank, what_.c_str());
      else
        std::fprintf(stderr,
                     "error: kozu render: rank %d was started with other settings than rank 0 (the scene, its "
                     "files, the flags or the frames differ); every rank stopped before rendering\n",
                     a.mismatched_rank);
    }
    return false;
#else
    (void)fingerprint;
    return status == 0;
#endif
  }

 private:
  std::string what_;
  bool passed_ = false;
};

// The scene a checkpoint belongs to: the scene file's bytes, each input file's name and size (hashing every
// texture's bytes would cost seconds; a file replaced by one of another size is caught) and the bytes of the scene
// files it includes.
uint64_t scene_hash(const RenderArgs& args, const Scene& scene) {
  const std::string text = args.demo ? std::string("kozu built-in demo scene") : read_input_file(args.scene);
  uint64_t h = hash_words(text.data(), text.size());
  for (const std::string& d : args.defines) h = hash_words(d.data(), d.size() + 1, h);  // with its NUL: "a","b" ≠ "ab"
  for (const auto& f : scene.input_files) {
    const std::string name = f.filename().string();
    std::error_code ec;
    const uint64_t size = std::filesystem::file_size(f, ec);
    h = hash_words(name.data(), name.size(), h);
    h = hash_words(&size, sizeof size, h);
    // Scene files the scene includes are part of its text: a changed value keeps their size.
    if (lower_extension(f) == ".json" && !ec) {
      const std::string included = read_input_file(f);
      h = hash_words(included.data(), included.size(), h);
    }
  }
  return h;
}

// The denoiser's time per pixel on 2 cores, for the --budget reserve: the filter 9-10 us and the visible emission's
// re-estimation at most 4 samples per pixel, 1.6 us (measured, docs/production.md).
constexpr double kDenoiseSecondsPerPixel = 14e-6;

// Under --budget EXR outputs are written uncompressed: zip gains about 10 % on a render's noisy floats and takes ten
// times as long (a 4K image: 3 s against 0.3 s), time the budget gives to sampling instead.
constexpr const char* kBudgetExrCompression = "none";

// What finishing an image output costs here and now, in seconds for `pixels`: two films of 160 x 90 and 320 x 180
// with most pixels unsampled turned into images (the hole filling a render stopped early needs) and written in the
// output's format into its folder, timed; their difference is the cost per pixel (at least the floor measured on
// a quiet 2-core machine, docs/production.md), the rest the fixed cost of a write. A loaded machine, a sanitizer
// build or a slow disk shows in them. `slowdown` is the measured cost per pixel over the floor's.
double write_seconds(const OutputFile& o, const ToneMap& tonemap, double pixels, double* slowdown) {
  const std::string ext = lower_extension(o.path);
  // Uncompressed EXR about 41 ns per pixel at 3840 x 2160 (with the film's conversion), zipped 270; PNG 185-250.
  const double floor = ext == ".exr" ? 60e-9 : ext == ".hdr" ? 270e-9 : 250e-9;
  std::filesystem::path probe = o.path;
  probe.replace_filename(fmt::format(".kozu-calibrate.{}{}", getpid(), ext));
  TempFileGuard guard(probe);  // removed on every exit path
  double t[2] = {0.0, 0.0};
  const int widths[2] = {160, 320};
  for (int k = 0; k < 2; ++k) {
    const int w = widths[k], h = w * 9 / 16;
    Film film(w, h);
    for (int y = 0; y < h; y += 8)
      for (int x = 0; x < w; x += 8) film.add_sample(x, y, Rgb(static_cast<float>((x * 7 + y * 13) % 100) * 0.01f));
    const auto start = std::chrono::steady_clock::now();
    try {
      ImageExtras extras;
      extras.exr_compression = kBudgetExrCompression;
      write_image(probe, w, h, film.rgb(), tonemap, extras);
    } catch (const std::exception&) {
      return floor * pixels;  // the real write will report its own error
    }
    t[k] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  const double n0 = 160.0 * 90.0, n1 = 320.0 * 180.0;
  const double per_pixel = std::max(floor, (t[1] - t[0]) / (n1 - n0));
  const double fixed = std::max(0.0, t[0] - per_pixel * n0);
  *slowdown = std::max(*slowdown, per_pixel / floor);
  return fixed + per_pixel * pixels;
}

// Seconds that finishing a frame takes after sampling, with margin: the --budget reserve, in three parts.
struct FinishCost {
  double raw = 0.0;       // the raw images (every image output when the denoiser is skipped) and a checkpoint
  double denoised = 0.0;  // the denoiser and the writes of the denoised images
  double fixed = 0.0;     // the statistics, the exit and the scheduler
  double total(bool denoise) const { return raw + fixed + (denoise ? denoised : 0.0); }
};
// The image writes (calibrated above), a checkpoint (56 bytes per pixel at 200 MB/s) and the denoiser, times 1.5;
// plus 0.25 s for the statistics, the exit and the scheduler, scaled by the calibration's slowdown (a machine 3 times
// slower than the floor gets 0.75 s).
FinishCost finish_seconds(Vec2i size, const std::vector<OutputFile>& outputs, const ToneMap& tonemap, bool checkpoint,
                          bool denoise, bool denoise_only) {
  const double pixels = static_cast<double>(size.x) * size.y;
  double raw = 0.0, denoised = 0.0, slowdown = 1.0;
  // One calibration per folder and format: outputs that share both cost the same.
  std::map<std::pair<std::filesystem::path, std::string>, double> measured;
  for (const auto& o : outputs) {
    if (!o.image) continue;
    const auto key = std::pair{o.path.parent_path(), lower_extension(o.path)};
    const auto it = measured.find(key);
    const double s = it != measured.end()
                         ? it->second
                         : measured.emplace(key, write_seconds(o, tonemap, pixels, &slowdown)).first->second;
    // --denoise-only writes its outputs raw first under a budget, then denoised if time allows.
    if (!o.denoised || denoise_only) raw += s;
    if (o.denoised) denoised += s;
  }
  if (checkpoint) raw += 56.0 * pixels / 200e6;
  if (denoise) denoised += kDenoiseSecondsPerPixel * slowdown * pixels;
  return {1.5 * raw, 1.5 * denoised, 0.25 * std::min(slowdown, 8.0)};
}

std::string join(const std::vector<std::string>& items, const char* none) {
  std::string s;
  for (const auto& i : items) s += (s.empty() ? "" : ", ") + i;
  return s.empty() ? none : s;
}

nlohmann::json render_stats(const Scene& scene, const std::string& scene_name, const RenderSettings& opt, int max_depth,
                            const RenderResult& result, double load_seconds, int signal,
                            const std::vector<std::string>& written) {
  const Vec2i res = scene.camera.resolution();
  const double paths_per_second = result.seconds > 0 ? result.paths / result.seconds : 0.0;
  nlohmann::json j;
  j["kozu_version"] = KOZU_VERSION;
  j["scene"] = scene_name;
  j["resolution"] = {res.x, res.y};
  j["spp"] = result.film.mean_spp;
  j["spp_min"] = result.film.min_spp;
  j["spp_max"] = result.film.max_spp;
  j["spp_target"] = opt.spp;
  j["warnings"] = scene.all_warnings();  // as printed on stderr at load
  j["max_depth"] = max_depth;
  j["seed"] = opt.seed;
  j["direct"] = direct_lighting_name(opt.direct);
  j["time_limit"] = opt.time_limit;
  j["hit_time_limit"] = result.hit_time_limit;
  j["interrupted"] = signal != 0;
  if (signal) j["signal"] = StopSignals::name(signal);
  j["load_seconds"] = load_seconds;
  j["render_seconds"] = result.seconds;
  j["paths"] = result.paths;
  j["paths_per_second"] = paths_per_second;
  j["samples_per_second"] = paths_per_second;
  j["rays_traced"] = result.rays.total();
  j["camera_rays"] = result.rays.camera_rays;
  j["extension_rays"] = result.rays.extension_rays;
  j["shadow_rays"] = result.rays.shadow_rays;
  j["probe_rays"] = result.rays.probe_rays;
  j["rays_per_second"] = result.seconds > 0 ? result.rays.total() / result.seconds : 0.0;
  j["truncated_paths"] = result.rays.truncated_paths;
  j["unsampled_pixels"] = result.film.unsampled_pixels;
  j["nan_pixels"] = result.film.pixels_with_discarded;
  j["nan_samples"] = result.film.discarded_samples;
  j["threads"] = result.threads;
  j["triangles"] = scene.triangle_count();
  j["shapes"] = scene.shapes.size();
  j["lights"] = scene.lights.size();
  j["peak_memory_bytes"] = peak_rss_bytes();
  nlohmann::json media = nlohmann::json::object();
  for (const auto& m : scene.media) {
    const Medium::Stats ms = m->stats();
    media[m->name] = {{"voxel_bytes", ms.bytes}};
    if (ms.lod >= 0) media[m->name]["lod"] = ms.lod;
  }
  j["media"] = media;
  if (scene.textures) {
    const TextureCache::Stats ts = scene.textures->stats();
    j["textures"] = {{"files", ts.files},
                     {"converted", ts.converted},
                     {"reused_conversions", ts.reused},
                     {"memory_mb", ts.memory_mb},
                     {"memory_limit_mb", ts.memory_limit_mb},
                     {"tile_lookups", ts.lookups},
                     {"hit_rate", ts.hit_rate},
                     {"tiles_read", ts.tiles_read},
                     {"mb_read", ts.mb_read}};
  }
  j["outputs"] = written;
  return j;
}

int run_render(const RenderArgs& args) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const std::string scene_name = args.demo ? "<demo>" : args.scene;
  if (args.demo == !args.scene.empty()) {
    print_error("kozu render: give a scene file or --demo (not both)");
    return 1;
  }
  // A stop signal before sampling ends the command at once (apps/stop_signals.h: loading a large scene or converting
  // a texture is not waited for; the output probes and conversions are registered temporary files).
  RenderProgress progress;
  RankGate ready("before rendering");
  if (!args.empty_flags.empty()) {
    print_error(fmt::format("kozu render: {}: expected a file name, got an empty one", args.empty_flags.front()));
    return 1;
  }
  // The command line and every output are checked before anything is loaded.
  RenderFlags flags;
  std::vector<OutputFile> outputs;
  for (const auto& o : args.outputs) outputs.push_back({o, "-o", true});
  const std::string stem = args.demo ? "demo" : std::filesystem::path(args.scene).stem().string();
  if (outputs.empty()) {
    outputs = {{std::filesystem::path("out") / (stem + ".exr"), "-o", true},
               {std::filesystem::path("out") / (stem + ".png"), "-o", true}};
  }
  if (!args.stats.empty()) outputs.push_back({args.stats, "--stats", false});
  if (args.denoise || args.denoise_only) {
    // --denoise writes NAME.denoised.EXT beside each image; --denoise-only writes the denoised image as NAME.EXT.
    std::vector<OutputFile> denoised;
    for (auto& o : outputs) {
      if (!o.image) continue;
      if (args.denoise_only) {
        o.denoised = true;
        continue;
      }
      auto p = o.path;
      p.replace_filename(p.stem().string() + ".denoised" + p.extension().string());
      denoised.push_back({p, "--denoise", true, true});
    }
    outputs.insert(outputs.end(), denoised.begin(), denoised.end());
  }
  if (!args.checkpoint.empty()) outputs.push_back({args.checkpoint, "--checkpoint", false});
  if (args.alpha)
    for (const auto& o : outputs)
      if (o.image && lower_extension(o.path) != ".exr") {
        // A PNG's alpha is unassociated (straight), but the colour of an edge pixel already holds the background
        // it covers partly: neither reading of an RGBA PNG would composite right.
        print_error(fmt::format(
            "kozu render: --alpha: {}: alpha goes into .exr outputs only (the colour of an edge pixel already holds "
            "the background, so an RGBA {} would composite wrong); give -o NAME.exr",
            o.path.string(), lower_extension(o.path)));
        return 1;
      }
  if (args.aov && std::none_of(outputs.begin(), outputs.end(),
                               [](const OutputFile& o) { return o.image && lower_extension(o.path) == ".exr"; })) {
    print_error("kozu render: --aov: AOVs are extra channels of .exr outputs, and no output is one; add -o NAME.exr");
    return 1;
  }
  // Files that are not scenes: said so, not answered with a JSON syntax error.
  if (!args.demo) {
    const std::string ext = lower_extension(args.scene);
    std::string why;
    if (ext == ".obj" || ext == ".ply")
      why = fmt::format(
          "{} mesh is not a scene (it has no camera or lights): place it in a scene file, e.g. {{\"shapes\": "
          "[{{\"type\": \"mesh\", \"file\": \"{}\"}}], ...}} (docs/scene-format.md), or render a .gltf/.glb",
          ext == ".obj" ? "an OBJ" : "a PLY", std::filesystem::path(args.scene).filename().string());
    else if (ext == ".blend")
      why =
          "kozu does not read .blend files: export the scene from Blender as glTF 2.0 (File > Export > glTF 2.0) and "
          "render the .glb (docs/cookbook.md)";
    else if (ext == ".fbx" || ext == ".usd" || ext == ".usda" || ext == ".usdc" || ext == ".usdz" || ext == ".abc" ||
             ext == ".dae" || ext == ".stl" || ext == ".3ds")
      why = fmt::format("kozu reads kozu scene files (.json) and glTF 2.0 (.gltf, .glb), not {}: convert it to glTF",
                        ext);
    else if (is_supported_output(args.scene) || ext == ".tx" || ext == ".tif" || ext == ".tiff")
      why = "an image is not a scene: give a scene file (.json) or a .gltf/.glb";
    if (!why.empty()) {
      print_error(fmt::format("{}: {}", args.scene, why));
      return 1;
    }
  }
  std::vector<std::filesystem::path> inputs;
  if (!args.demo) inputs.emplace_back(args.scene);
  try {
    flags = validate_flags(args);
    check_outputs(outputs, inputs);
  } catch (const std::exception& e) {
    print_error(e.what());
    return 1;
  }
  if (flags.threads > max_render_threads()) {
    std::fprintf(stderr, "warning: --threads %d: using %d (4 x the %u hardware threads)\n", flags.threads,
                 max_render_threads(), std::thread::hardware_concurrency());
    flags.threads = max_render_threads();
  }

  std::unique_ptr<Scene> scene;
  try {
    // Images that are not tiled mip-mapped textures are converted once into a folder beside the first output.
    SceneLoadOptions load;
    load.textures.memory_mb = flags.texture_cache_mb;
    load.textures.convert_dir = outputs.front().path.parent_path() / ".kozu-tx";
    load.overrides = flags.overrides;
    // A .gltf or .glb file is a scene of its own (its camera, lights or a default environment).
    const std::string ext = args.demo ? "" : lower_extension(args.scene);
    scene = args.demo                         ? load_demo_scene(load)
            : ext == ".gltf" || ext == ".glb" ? load_gltf_file(args.scene, load)
                                              : load_scene_file(args.scene, load);
    if (flags.resolution) {
      scene->camera.set_resolution(*flags.resolution);
      scene->set_media_view();
    }
    for (const std::string& w : scene->all_warnings()) std::fprintf(stderr, "warning: %s\n", w.c_str());
    check_outputs(outputs, scene->input_files);
  } catch (const InputError& e) {
    print_error(e.what() + override_note(flags.overrides, e.json_path()));
    return 1;
  } catch (const std::bad_alloc&) {
    print_error(scene_name + ": out of memory while loading the scene");
    return 1;
  } catch (const std::exception& e) {
    print_error(scene_name + ": " + e.what());
    return 1;
  }
  const double load_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  if (const int sig = StopSignals::received()) {
    print_error(
        fmt::format("{}: interrupted by {} before rendering; nothing written", scene_name, StopSignals::name(sig)));
    return 128 + sig;
  }

  // The scene's settings, overridden by the flags.
  RenderSettings opt = scene->settings;
  // --time-limit or --budget alone asks for "as many samples as fit": it lifts the scene's sample cap.
  const bool timed = (flags.time_limit && *flags.time_limit > 0.0) || flags.budget;
  opt.spp = flags.spp.value_or(timed ? 0 : scene->settings.spp);
  if (flags.sample_range) {
    opt.sample_begin = flags.sample_range->x;
    opt.spp = flags.sample_range->y;
  }
  if (flags.time_limit) opt.time_limit = *flags.time_limit;
  opt.threads = flags.threads;
  if (flags.seed) opt.seed = *flags.seed;
  if (flags.max_depth) opt.max_depth = *flags.max_depth;
  if (flags.direct) opt.direct = *flags.direct;
  if (const auto problem = flags.budget ? std::nullopt : sample_limit_problem(opt)) {
    print_error("kozu render: --spp: " + *problem);
    return 1;
  }
  const int max_depth = opt.max_depth;
  const Vec2i res = scene->camera.resolution();
  // Under mpirun every rank renders its share of the tiles; rank 0 gathers the film and writes the outputs.
  const Ranks ranks = mpi_ranks();
  opt.tile_rank = ranks.rank;
  opt.tile_ranks = ranks.size;
  if (ranks.distributed() && (flags.partial_every || flags.checkpoint_every)) {
    print_error(
        "kozu render: --partial-every and --checkpoint-every are not supported across MPI ranks (each rank "
        "holds only its tiles until the end); the final images and --checkpoint are");
    return 1;
  }
  PixelWindow window{Vec2i(0), res};
  if (args.crop) {
    try {
      window = crop_flag(*args.crop, res);
    } catch (const InputError& e) {
      print_error(e.what());
      return 1;
    }
  }

  // The film and the output buffers are the render's big allocations: check that they fit first.
  const RenderMemory need = render_memory(window.size, !flags.aovs.empty() || flags.sample_range || args.crop);
  const MemoryLimit limit = memory_limit();
  const double left = static_cast<double>(limit.bytes) - static_cast<double>(current_rss_bytes());
  if (need.total() > left) {
    print_error(
        fmt::format("{}: a {}x{} render needs about {} (film {}, image buffers {}) but only {} of the {} "
                    "limit ({}) is left; lower the resolution",
                    scene_name, window.size.x, window.size.y, format_bytes(need.total()), format_bytes(need.film),
                    format_bytes(need.buffers), format_bytes(std::max(left, 0.0)),
                    format_bytes(static_cast<double>(limit.bytes)), limit.source));
    return 1;
  }

  // Animation: the frames to render and each one's output names.
  const bool animated = scene->animation.animated();
  Vec2i frames(0, 0);
  if (args.frames && !animated) {
    print_error(
        fmt::format("kozu render: --frames: {} has no \"animation\" block (docs/production.md#animation)", scene_name));
    return 1;
  }
  if (animated) {
    frames = Vec2i(0, scene->animation.frames - 1);
    if (args.frames) {
      try {
        frames = frames_flag(*args.frames, scene->animation.frames);
      } catch (const InputError& e) {
        print_error(e.what());
        return 1;
      }
    }
  }
  const bool several_frames = frames.y > frames.x;
  const bool stats_per_frame = !args.stats.empty() && has_frame_pattern(args.stats);
  if (several_frames && args.outputs.empty()) {
    // The default outputs of an animation: out/<scene>/0000.exr and .png, ...
    for (auto& o : outputs)
      if (o.image) o.path = o.path.parent_path() / stem / ("%04d" + o.path.extension().string());
  }
  if (several_frames) {
    for (const auto& o : outputs)
      if (o.image && !has_frame_pattern(o.path.string())) {
        print_error(
            fmt::format("kozu render: {} {}: {} frames would overwrite one file: put the frame number in the "
                        "name, e.g. out/%04d.png",
                        o.flag, o.path.string(), frames.y - frames.x + 1));
        return 1;
      }
    if (!args.checkpoint.empty() || !args.resume.empty()) {
      print_error("kozu render: --checkpoint and --resume take one frame at a time: render each frame with --frames N");
      return 1;
    }
  }
  const std::vector<OutputFile>& all_outputs = outputs;
  auto frame_outputs = [&](int frame) {
    std::vector<OutputFile> out = all_outputs;
    for (auto& o : out) o.path = frame_path(o.path.string(), frame);
    return out;
  };
  // Every frame's outputs are checked before the first frame is rendered (a folder named like frame 1, or a file
  // name too long for the folder once numbered, once stopped an animation after frame 0): the first and the last
  // frame's outputs fully (their folders created and probed, as a still's), every frame's for what is there already
  // (a folder, a FIFO or a device under the name) and for the render's inputs.
  if (animated) {
    try {
      check_outputs(frame_outputs(frames.x), scene->input_files);
      if (frames.y != frames.x) check_outputs(frame_outputs(frames.y), scene->input_files);
      for (const OutputFile& o : outputs) check_numbered_output(o, frames, scene->input_files);
    } catch (const std::exception& e) {
      print_error(e.what());
      return 1;
    }
  }
  const CameraKey still = camera_key(scene->camera);
  // The scene's identity for checkpoints: its file's bytes and its inputs' names and sizes, read once for all frames.
  const uint64_t base_scene_hash = scene_hash(args, *scene);

  // One frame (a still is frame 0 of one): its camera, seed and outputs, rendered and written.
  const RenderSettings base_opt = opt;
  // --budget: the finishing costs (calibrated on the first frame), whether the denoiser fits, the reserve of the
  // current frame and the time the last frame took besides sampling.
  std::optional<FinishCost> finish_cost;
  bool denoise_planned = false;
  double reserve = 0.0, frame_overhead = 0.0;
  constexpr int kBudgetSpent = -1;  // render_frame: the budget has no room for this frame
  std::vector<nlohmann::json> frame_stats;
  auto render_frame = [&](int frame, int frames_left) -> int {
    const auto frame_start = Clock::now();
    RankGate frame_ready(fmt::format("before frame {}", frame));
    RenderSettings fopt = base_opt;
    const std::vector<OutputFile> frame_outs = animated ? frame_outputs(frame) : all_outputs;
    if (animated) {
      // A different seed per frame: noise that stays put from frame to frame reads as a dirty lens.
      fopt.seed = base_opt.seed + static_cast<uint64_t>(frame) * 0x9e3779b97f4a7c15ull;
      const Animation& anim = scene->animation;
      const double time = anim.frame_time(frame);
      // The frame's camera (for the media's level of detail, and every sample without a shutter), then the poses
      // across the open shutter.
      const auto camera_at = [&](double t) {
        const CameraKey key = anim.camera_at(t, still);
        return scene->camera.moved(key.position, key.look_at, key.fov);
      };
      double at = time;
      try {
        scene->camera = camera_at(time);
        scene->shutter_cameras.clear();
        if (anim.shutter)
          for (const double t : anim.shutter_times(frame)) scene->shutter_cameras.push_back(camera_at(at = t));
      } catch (const std::invalid_argument& e) {
        print_error(
            fmt::format("{}: /animation/camera: at frame {} (t = {:.4g} s): {}", scene_name, frame, at, e.what()));
        return 1;
      }
      if (scene->has_media()) scene->set_media_view();
      // Moving shapes: their poses, then the hierarchy rebuilt (a camera-only animation keeps the first build).
      try {
        scene->pose_shapes(time);
      } catch (const std::invalid_argument& e) {
        print_error(fmt::format("{}: /animation/shapes: at frame {}: {}", scene_name, frame, e.what()));
        return 1;
      }
      progress.samples_done = 0;
    }
    // What a checkpoint must match to be continued.
    RenderIdentity identity;
    identity.kozu_version = KOZU_VERSION;
    identity.scene_hash = base_scene_hash ^ (animated ? hash_words(&frame, sizeof frame) : 0);
    identity.seed = fopt.seed;
    identity.max_depth = max_depth;
    identity.direct = direct_lighting_name(fopt.direct);
    identity.filter = PixelFilter::name(fopt.filter);
    identity.resolution = res;
    identity.window_origin = window.origin;
    identity.window_size = window.size;
    identity.sample_begin = fopt.sample_begin;
    // Parts of a split render carry their per-pixel sample counts, for kozu merge.
    std::vector<Aov> aovs = flags.aovs;
    if ((flags.sample_range || args.crop) && std::find(aovs.begin(), aovs.end(), Aov::SampleCount) == aovs.end())
      aovs.push_back(Aov::SampleCount);
    identity.features = needs_features(aovs) || args.denoise || args.denoise_only;
    identity.alpha = args.alpha;
    Film film;
    try {
      film = args.resume.empty() ? Film(window.size.x, window.size.y, window.origin)
                                 : load_checkpoint(args.resume, identity);
      if (identity.features && !film.has_features()) film.enable_features();
      if (identity.alpha && !film.has_alpha()) film.enable_alpha();
      if (ranks.distributed() && !args.resume.empty()) {
        // Each rank keeps the resumed samples of its own tiles only: the final sum must hold each pixel once.
        for (int y = 0; y < window.size.y; ++y)
          for (int x = 0; x < window.size.x; ++x) {
            const Vec2i p = window.origin + Vec2i(x, y);
            if (renders_pixel(film, fopt, p)) continue;
            const size_t i = static_cast<size_t>(y) * window.size.x + x;
            film.pixels()[i] = Film::Pixel{};
            if (film.has_features()) film.feature_pixels()[i] = Film::FeaturePixel{};
            if (film.has_alpha()) film.hit_counts()[i] = 0;
          }
      }
    } catch (const InputError& e) {
      print_error(e.what());
      return 1;
    }
    const Film::Summary resumed = film.summary();

    PathIntegrator integrator(*scene, max_depth, fopt.direct);
    // Writes every image output from the film as it is (a partial image, or the final one).
    double render_seconds = 0.0, denoise_seconds = 0.0;
    EmissionRefineStats refined;
    const bool denoising = args.denoise || args.denoise_only;
    // Under --budget the raw images are written first and the denoised ones only when the denoiser and their writes
    // still fit (`denoise_deadline`, seconds since the process started); --denoise-only then writes the raw image
    // under its names first, replaced by the denoised one if it fits.
    double denoise_deadline = std::numeric_limits<double>::infinity();
    bool denoise_skipped = false;
    auto write_images = [&](bool partial, std::vector<std::string>& written, std::vector<std::string>& failures) {
      const std::vector<float> rgb = film.rgb();
      ImageExtras extras;
      if (flags.budget) extras.exr_compression = kBudgetExrCompression;
      extras.origin = window.origin;
      extras.full_size = res;
      const Film::Summary sum = film.summary();
      extras.attributes = {{"kozu:version", KOZU_VERSION},
                           {"kozu:scene_hash", fmt::format("{:016x}", identity.scene_hash)},
                           {"kozu:seed", std::to_string(fopt.seed)},
                           {"kozu:sample_begin", std::to_string(fopt.sample_begin)},
                           {"kozu:spp_mean", fmt::format("{}", sum.mean_spp)},
                           {"kozu:spp_min", std::to_string(sum.min_spp)},
                           {"kozu:spp_max", std::to_string(sum.max_spp)},
                           {"kozu:render_seconds", fmt::format("{:.3f}", render_seconds)},
                           {"kozu:partial", partial ? "1" : "0"}};
      // OpenEXR's standard camera attributes, of the frame's camera (scene/camera.h gives the conventions).
      extras.matrices = {{"worldToCamera", scene->camera.exr_world_to_camera()}};
      if (const auto ndc = scene->camera.exr_world_to_ndc()) extras.matrices.emplace_back("worldToNDC", *ndc);
      if (args.alpha) {
        // OpenEXR's alpha channel: coverage, the fraction of the pixel's samples whose camera ray met geometry.
        extras.channels = {"A"};
        extras.data = film.alpha();
      }
      add_aov_channels(film, aovs, extras);
      std::vector<std::optional<std::string>> errors(frame_outs.size());
      std::vector<bool> wrote(frame_outs.size(), false);
      // The images are written in parallel (compression is most of a write).
      const auto write_all = [&](const std::vector<float>& pixels, auto&& takes) {
        tbb::parallel_for(size_t{0}, frame_outs.size(), [&](size_t i) {
          const OutputFile& o = frame_outs[i];
          if (!o.image || !takes(o)) return;
          try {
            write_image(o.path, window.size.x, window.size.y, pixels, flags.tonemap, extras);
            wrote[i] = true;
            errors[i].reset();
          } catch (const std::exception& e) {
            errors[i] = e.what();
          }
        });
      };
      // Partial images are the raw render only (denoising takes seconds), under every name but the extra
      // NAME.denoised ones.
      const bool budgeted = flags.budget.has_value();
      if (partial || !denoising) {
        write_all(rgb, [&](const OutputFile& o) { return !o.denoised || args.denoise_only; });
      } else {
        write_all(rgb, [&](const OutputFile& o) { return !o.denoised || (args.denoise_only && budgeted); });
        if (seconds_since_process_start() <= denoise_deadline) {
          const auto t = Clock::now();
          // The visible emission re-estimated where its samples disagree (render/emission_refine.h), then the rest
          // filtered.
          const VisibleEmission emission = refine_emission(*scene, integrator, film, fopt, {}, &refined);
          const std::vector<float> clean = denoise(film, {}, &emission);
          denoise_seconds = std::chrono::duration<double>(Clock::now() - t).count();
          write_all(clean, [](const OutputFile& o) { return o.denoised; });
        } else {
          denoise_skipped = true;
        }
      }
      for (size_t i = 0; i < frame_outs.size(); ++i) {
        if (wrote[i]) written.push_back(frame_outs[i].path.string());
        if (errors[i]) failures.push_back(*errors[i]);
      }
    };

    // --budget: sampling ends when what is left of the budget, measured from the process's start, is what the
    // writes need (estimated from the image size, with margin); frames still to render share it equally. A frame is
    // begun only when its setting up and writing still fit, so the frames stop when the budget does.
    if (flags.budget && !finish_cost) {
      finish_cost = finish_seconds(window.size, frame_outs, flags.tonemap, !args.checkpoint.empty(), denoising,
                                   args.denoise_only);
      // The denoiser is planned for only when every frame's share of it leaves a quarter of the budget to sampling;
      // otherwise the raw images are the product, denoised only where sampling ended early (a sample cap).
      const double budget_left = *flags.budget - seconds_since_process_start();
      denoise_planned = denoising && frames_left * finish_cost->total(true) <= 0.75 * budget_left;
      // A budget that cannot hold even the writes of the raw images, as measured without the margin, is refused
      // now rather than overrun.
      const double writes = finish_cost->raw / 1.5;
      if (writes > budget_left) {
        print_error(fmt::format(
            "{}: --budget {}: writing the images at {}x{} takes about {:.2f} s here (measured) and {:.2f} s of the "
            "budget are left after loading; raise the budget, lower the resolution or write fewer outputs; nothing "
            "rendered",
            scene_name, *flags.budget, window.size.x, window.size.y, writes, std::max(budget_left, 0.0)));
        return 1;
      }
    }
    if (flags.budget) {
      const double now = seconds_since_process_start();
      // What a frame costs besides sampling: the calibrated writes until a frame was measured, then what the last
      // one took (setting it up, the hierarchy, the writes) with margin; the statistics and the exit once.
      const double calibrated = finish_cost->total(denoise_planned) - finish_cost->fixed;
      const double per_frame = frame > frames.x ? std::max(1.25 * frame_overhead, finish_cost->raw / 1.5) : calibrated;
      reserve = per_frame + finish_cost->fixed;
      if (frame > frames.x && now + reserve > *flags.budget) return kBudgetSpent;
      const double sampling =
          std::max((*flags.budget - now - finish_cost->fixed - per_frame * frames_left) / frames_left, 1e-6);
      denoise_deadline = *flags.budget - finish_cost->fixed - finish_cost->denoised;
      progress.deadline =
          Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(sampling));
      // The time limit only sizes the progress bar's ETA; the deadline above ends sampling.
      fopt.time_limit = fopt.time_limit > 0.0 ? std::min(fopt.time_limit, sampling) : sampling;
    }

    // Partial images and checkpoints between passes.
    int partial_images = 0, checkpoints = 0;
    std::vector<std::string> partial_failures;
    PassHook hook;
    const auto render_start = Clock::now();
    auto since_start = [&] { return std::chrono::duration<double>(Clock::now() - render_start).count(); };
    double next_partial = flags.partial_every.value_or(0.0), next_checkpoint = flags.checkpoint_every.value_or(0.0);
    if (flags.partial_every || flags.checkpoint_every) {
      hook.interval = std::min(flags.partial_every.value_or(1e30), flags.checkpoint_every.value_or(1e30));
      hook.every = [&] {
        const double t = since_start();
        render_seconds = t;
        if (flags.partial_every && t >= next_partial) {
          std::vector<std::string> written;
          write_images(true, written, partial_failures);
          ++partial_images;
          next_partial = since_start() + *flags.partial_every;
        }
        if (flags.checkpoint_every && t >= next_checkpoint) {
          try {
            save_checkpoint(args.checkpoint, identity, film);
            ++checkpoints;
          } catch (const std::exception& e) {
            partial_failures.push_back(e.what());
          }
          next_checkpoint = since_start() + *flags.checkpoint_every;
        }
      };
    }
    // A signal while the frame was set up: nothing of it was sampled (a resumed film still has its samples to write).
    // Under MPI that rank's stop is agreed on like a failure, so no rank waits for it in the reduction.
    const int early_signal = resumed.total_samples == 0 ? StopSignals::received() : 0;
    if (!frame_ready.pass(early_signal ? 128 + early_signal : 0, static_cast<uint64_t>(frame))) {
      if (!early_signal) return 1;
      print_error(fmt::format("{}: interrupted by {} before frame {} was rendered; nothing written for it", scene_name,
                              StopSignals::name(early_signal), frame));
      return 128 + early_signal;
    }
    // From here a stop signal ends sampling, and the images are still written.
    std::optional<ProgressBar> bar;
    if (!args.quiet && ranks.rank == 0 && isatty(STDERR_FILENO))
      bar.emplace(progress,
                  static_cast<uint64_t>(std::max(fopt.spp - fopt.sample_begin, 0)) * window.size.x * window.size.y,
                  fopt.time_limit);
    RenderResult result = render(*scene, integrator, film, fopt, &progress, hook);
    if (bar) bar->stop();
    render_seconds = result.seconds;
    const auto finish_start = Clock::now();
#ifdef KOZU_HAVE_MPI
    if (ranks.distributed()) {
      const MpiWorld& world = *MpiWorld::instance();
      if (!world.reduce(film, result.rays, result.paths)) return 1;
      result.seconds = world.max(result.seconds);
      if (ranks.rank != 0) {
        const int sig = StopSignals::received();
        return sig ? 128 + sig : 0;  // rank 0 writes
      }
      result.film = film.summary();
      render_seconds = result.seconds;
    }
#endif

    // Every output is attempted; failures are reported with what was written.
    std::vector<std::string> written, failures;
    // A partial write that failed is reported once, unless the final write of that output then worked.
    write_images(false, written, failures);
    if (!args.checkpoint.empty()) {
      try {
        save_checkpoint(args.checkpoint, identity, film);
        ++checkpoints;
        written.push_back(args.checkpoint);
      } catch (const std::exception& e) {
        failures.push_back(e.what());
      }
    }
    const int signal = StopSignals::received();
    if (!args.stats.empty()) {
      try {
        nlohmann::json j = render_stats(*scene, scene_name, fopt, max_depth, result, load_seconds, signal, written);
        if (animated) j["frame"] = frame;
        if (flags.budget) {
          j["budget"] = *flags.budget;
          j["budget_reserve_seconds"] = reserve;
        }
        j["partial_images"] = partial_images;
        if (denoising) {
          j["denoise_seconds"] = denoise_seconds;
          j["denoise_emission_pixels"] = refined.pixels;
          j["denoise_emission_samples"] = refined.samples;
          j["denoise_emission_seconds"] = refined.seconds;
        }
        j["checkpoints"] = checkpoints;
        if (!args.resume.empty()) {
          j["resumed_from"] = args.resume;
          j["resumed_samples"] = resumed.total_samples;
        }
        j["sample_begin"] = fopt.sample_begin;
        j["mpi_ranks"] = ranks.size;
        j["window"] = {window.origin.x, window.origin.y, window.size.x, window.size.y};
        j["write_seconds"] = std::chrono::duration<double>(Clock::now() - finish_start).count();
        j["process_seconds"] = seconds_since_process_start();
        if (stats_per_frame || !several_frames)
          write_file_atomic(frame_path(args.stats, frame),
                            j.dump(2, ' ', false, Json::error_handler_t::replace) + "\n");
        else
          frame_stats.push_back(j);
      } catch (const std::exception& e) {
        failures.push_back(e.what());
      }
    }
    if (failures.empty() && !partial_failures.empty()) {
      std::fprintf(stderr, "warning: %zu partial write%s failed, the first: %s\n", partial_failures.size(),
                   partial_failures.size() == 1 ? "" : "s", partial_failures.front().c_str());
    }

    const uint64_t pixels = static_cast<uint64_t>(window.size.x) * window.size.y;
    if (result.film.unsampled_pixels > 0)
      std::fprintf(stderr,
                   "warning: %s: %llu of %llu pixels (%.2f%%) have no valid sample (the render stopped before "
                   "reaching them, or all of theirs were NaN); they were filled from their neighbours\n",
                   scene_name.c_str(), static_cast<unsigned long long>(result.film.unsampled_pixels),
                   static_cast<unsigned long long>(pixels), 100.0 * result.film.unsampled_pixels / pixels);
    if (result.rays.truncated_paths > 0)
      std::fprintf(stderr,
                   "warning: %s: %llu paths reached the cap of %u tentative collisions in media and ended there (a "
                   "medium's density times its size is too large to track; see docs/volumes.md)\n",
                   scene_name.c_str(), static_cast<unsigned long long>(result.rays.truncated_paths),
                   PathBudget::kMaxCollisions);
    if (!args.quiet) {
      const double paths_per_second = result.seconds > 0 ? result.paths / result.seconds : 0.0;
      const double rays_per_second = result.seconds > 0 ? result.rays.total() / result.seconds : 0.0;
      std::fprintf(stderr, "kozu: %s%s%s %dx%d, %.1f spp in %.2f s (%spaths/s, %srays/s, %d threads%s), wrote %s\n",
                   signal ? fmt::format("interrupted by {}: ", StopSignals::name(signal)).c_str() : "",
                   scene_name.c_str(), animated ? fmt::format(" frame {}", frame).c_str() : "", res.x, res.y,
                   result.film.mean_spp, result.seconds, format_rate(paths_per_second).c_str(),
                   format_rate(rays_per_second).c_str(), result.threads,
                   result.film.discarded_samples
                       ? fmt::format(", {} NaN samples discarded", result.film.discarded_samples).c_str()
                       : "",
                   join(written, "nothing").c_str());
    }
    if (denoise_skipped)
      std::fprintf(stderr,
                   "warning: %s%s: --denoise: skipped: the denoiser needs about %.1f s at %dx%d, which the --budget "
                   "did not leave; %s\n",
                   scene_name.c_str(), animated ? fmt::format(" frame {}", frame).c_str() : "",
                   finish_cost ? finish_cost->denoised : 0.0, window.size.x, window.size.y,
                   args.denoise_only ? "the raw image was written under its names" : "the raw images were written");
    for (const auto& f : failures) print_error(f);
    frame_overhead = std::chrono::duration<double>(Clock::now() - frame_start).count() - std::max(result.seconds, 0.0);
    int status = signal ? 128 + signal : 0;  // as the signal's default action would report it (130, 143, 129)
    if (!failures.empty()) {
      print_error(fmt::format("{} output{} failed; written: {}", failures.size(), failures.size() == 1 ? "" : "s",
                              join(written, "none")));
      status = 1;
    }

    return status;
  };
  // Every rank loaded the scene and agrees on what to render (the fingerprint: what decides which pixels and
  // samples a rank takes, and the film's layout).
  {
    uint64_t f = base_scene_hash;
    const auto mix = [&f](const auto& v) { f = hash_words(&v, sizeof v, f); };
    for (const auto v : {res.x, res.y, window.origin.x, window.origin.y, window.size.x, window.size.y, opt.spp,
                         opt.sample_begin, opt.max_depth, frames.x, frames.y, static_cast<int>(opt.direct),
                         static_cast<int>(opt.filter), static_cast<int>(flags.aovs.size()), int{args.alpha},
                         int{args.denoise || args.denoise_only}, int{!args.resume.empty()}})
      mix(v);
    mix(opt.seed);
    if (!ready.pass(0, f)) return 1;
  }
  // From here the first stop signal ends sampling, and the images of the samples taken are still written.
  const StopSignals::Cooperative cooperative(progress.cancel);
  int status = 0, frame = frames.x;
  for (; frame <= frames.y && status == 0; ++frame) status = render_frame(frame, frames.y - frame + 1);
  if (status == kBudgetSpent) {
    // The frames that were begun are on disk; the rest would have overrun the budget.
    --frame;
    print_error(
        fmt::format("{}: --budget {}: frames {}..{} were not rendered: each frame needs about {:.3g} s to be "
                    "set up and written here, and {:.3g} s were left",
                    scene_name, *flags.budget, frame, frames.y, reserve - finish_cost->fixed,
                    std::max(*flags.budget - seconds_since_process_start(), 0.0)));
    status = 1;
  }
  if (!frame_stats.empty() && ranks.rank == 0) {
    try {
      nlohmann::json j;
      j["frames"] = frame_stats;
      j["process_seconds"] = seconds_since_process_start();
      if (flags.budget) j["budget"] = *flags.budget;
      write_file_atomic(args.stats, j.dump(2, ' ', false, Json::error_handler_t::replace) + "\n");
    } catch (const std::exception& e) {
      print_error(e.what());
      status = status ? status : 1;
    }
  }
  if (flags.budget && !ranks.distributed()) {
    // Everything is on disk: under a budget the scene's teardown (a large BVH, the texture cache) is skipped (not
    // under MPI, which must be finalized).
    std::fflush(nullptr);
    std::_Exit(status);
  }
  return status;
}

}  // namespace

Command add_render_command(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* cmd = app.add_subcommand("render", "Render a scene to EXR/PNG images");
  cmd->add_option("scene", args->scene, "Scene file (JSON, see docs/scene-format.md), or a .gltf/.glb file");
  cmd->add_flag("--demo", args->demo, "Render the built-in demo scene (no files needed)");
  cmd->add_option("-D,--define", args->defines,
                  "Override a scene key by its JSON path, PATH=VALUE (-D /camera/fov=30); repeatable; VALUE is JSON, "
                  "or a string")
      ->expected(1)
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
      ->type_name("PATH=VALUE");
  cmd->add_option("-o,--output", args->outputs,
                  "Output image; repeat for several. .exr/.hdr: linear float RGB; .png/.jpg: tone-mapped sRGB "
                  "(default: out/<scene>.exr and out/<scene>.png)");
  cmd->add_option("--spp", args->spp,
                  "Samples per pixel, an integer >= 0 (overrides render.spp; 0 = until the time limit)");
  cmd->add_option("--time-limit", args->time_limit,
                  "Stop sampling after this many seconds (loading excluded); without --spp, samples until then");
  cmd->add_option("--threads", args->threads, "Worker threads (default: all cores; at most 4 x the cores)");
  cmd->add_option("--seed", args->seed, "Random seed, an integer >= 0 (overrides render.seed)");
  cmd->add_option("--resolution", args->resolution,
                  "Image size WIDTHxHEIGHT, each in [1, 65536] (overrides camera.resolution)");
  cmd->add_option("--max-depth", args->max_depth,
                  "Maximum path length in bounces, in [0, 1024] (overrides render.max_depth)");
  cmd->add_option("--direct", args->direct,
                  "Direct light from quad/polygon lights: sample (default), ltc (closed form + stochastic shadows, "
                  "unbiased), ltc-ratio (Heitz et al. 2018, biased) or ltc-preview (closed form, no shadows) "
                  "(overrides render.direct)");
  cmd->add_option("--stats", args->stats, "Write render statistics as JSON to this file");
  cmd->add_option("--texture-cache-mb", args->texture_cache_mb,
                  "Memory for texture tiles in MiB, in [16, 1048576] (default 1024); more is read from disk again");
  cmd->add_option("--tonemap", args->tonemap, "Display transform for .png/.jpg: aces, neutral, agx or clamp")
      ->capture_default_str();
  cmd->add_option("--exposure", args->exposure,
                  "Exposure in stops applied before the tone map, in [-64, 64] (default 0)");
  cmd->add_flag("-q,--quiet", args->quiet, "No progress bar and no summary line");
  // Production (docs/production.md).
  cmd->add_option("--budget", args->budget,
                  "Whole-run limit in seconds from the process's start (loading, sampling, writing): the images are "
                  "on disk before it");
  cmd->add_option("--partial-every", args->partial_every,
                  "Write the current images every this many seconds while rendering (atomically)");
  cmd->add_option("--checkpoint", args->checkpoint,
                  "Save the film here at the end (and with --checkpoint-every, periodically) for --resume");
  cmd->add_option("--checkpoint-every", args->checkpoint_every, "Seconds between checkpoints (needs --checkpoint)");
  cmd->add_option("--resume", args->resume,
                  "Continue the render saved in this checkpoint (same scene, seed and settings) to the requested spp");
  cmd->add_option("--crop", args->crop,
                  "Render only pixels X0..X1-1, Y0..Y1-1: X0,Y0,X1,Y1 (the EXR keeps its place in the full image)");
  cmd->add_flag("--denoise", args->denoise,
                "Also write a denoised image beside each output (NAME.denoised.EXT); see docs/production.md");
  cmd->add_flag("--denoise-only", args->denoise_only, "Write only the denoised image, under the output names");
  cmd->add_option("--frames", args->frames,
                  "Frames of the scene's animation to render: A:B (both included) or N (outputs need a %04d pattern)");
  cmd->add_option("--aov", args->aov,
                  "Extra EXR channels: a comma list of albedo, normal, depth, position, variance, sample_count");
  cmd->add_flag("--alpha", args->alpha,
                "Write coverage as an A channel in the EXRs (the fraction of each pixel's camera samples that hit "
                "geometry); .exr outputs only");
  cmd->add_option("--sample-range", args->sample_range,
                  "Render samples A..B-1 of every pixel: A:B (parts of disjoint ranges combine with kozu merge)");
  return [args, cmd] {
    for (const char* flag : {"--stats", "--checkpoint", "--resume", "--output"})
      if (cmd->count(flag) > 0)
        for (const std::string& v : cmd->get_option(flag)->as<std::vector<std::string>>())
          if (v.empty()) args->empty_flags.push_back(std::string(flag) == "--output" ? "-o" : flag);
    return run_render(*args);
  };
}

}  // namespace kozu::app
