// `kozu render`: load a scene, render it progressively, write images and statistics.
#include "apps/commands.h"
#include "apps/output_paths.h"
#include "apps/stop_signals.h"
#include "core/error.h"
#include "core/file_io.h"
#include "core/memory.h"
#include "core/version.h"
#include "integrators/path.h"
#include "io/image_io.h"
#include "media/medium.h"
#include "render/renderer.h"
#include "scene/render_settings.h"
#include "scene/scene_loader.h"

#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <cstdio>
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
  return f;
}

// Bytes a w × h render allocates (an estimate with margin): the film, and for writing the linear RGB floats,
// the writer's copy of them, the hole-filling pyramid (4/3 × 16 bytes) and the 8-bit RGB.
struct RenderMemory {
  double film = 0, buffers = 0;
  double total() const { return film + buffers; }
};
RenderMemory render_memory(Vec2i res) {
  const double pixels = static_cast<double>(res.x) * res.y;
  return {pixels * static_cast<double>(Film::bytes_per_pixel()), pixels * (12.0 + 12.0 + 22.0 + 3.0)};
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

void print_error(const std::string& message) { std::fprintf(stderr, "error: %s\n", message.c_str()); }

std::string join(const std::vector<std::string>& items, const char* none) {
  std::string s;
  for (const auto& i : items) s += (s.empty() ? "" : ", ") + i;
  return s.empty() ? none : s;
}

nlohmann::json render_stats(const Scene& scene, const std::string& scene_name, const RenderSettings& opt,
                            int max_depth, const RenderResult& result, double load_seconds, int signal,
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
    j["textures"] = {{"files", ts.files},         {"converted", ts.converted}, {"reused_conversions", ts.reused},
                     {"memory_mb", ts.memory_mb}, {"memory_limit_mb", ts.memory_limit_mb},
                     {"tile_lookups", ts.lookups}, {"hit_rate", ts.hit_rate},
                     {"tiles_read", ts.tiles_read}, {"mb_read", ts.mb_read}};
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
  // Stop signals are caught from the start: one during loading or the output checks ends the command before it
  // renders (the output probes are temporary files too, removed on every exit path).
  RenderProgress progress;
  StopSignals signals(progress.cancel);
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
    // A .gltf or .glb file is a scene of its own (its camera, lights or a default environment).
    const std::string ext = args.demo ? "" : lower_extension(args.scene);
    scene = args.demo                           ? load_demo_scene(load)
            : ext == ".gltf" || ext == ".glb" ? load_gltf_file(args.scene, load)
                                              : load_scene_file(args.scene, load);
    for (const std::string& w : scene->warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    if (flags.resolution) {
      scene->camera.set_resolution(*flags.resolution);
      scene->set_media_view();
    }
    check_outputs(outputs, scene->input_files);
  } catch (const InputError& e) {
    print_error(e.what());
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
    print_error(fmt::format("{}: interrupted by {} before rendering; nothing written", scene_name,
                            StopSignals::name(sig)));
    return 128 + sig;
  }

  // The scene's settings, overridden by the flags.
  RenderSettings opt = scene->settings;
  // --time-limit alone asks for "as many samples as fit": it lifts the scene's sample cap.
  opt.spp = flags.spp.value_or(flags.time_limit && *flags.time_limit > 0.0 ? 0 : scene->settings.spp);
  if (flags.time_limit) opt.time_limit = *flags.time_limit;
  opt.threads = flags.threads;
  if (flags.seed) opt.seed = *flags.seed;
  if (flags.max_depth) opt.max_depth = *flags.max_depth;
  if (flags.direct) opt.direct = *flags.direct;
  if (const auto problem = sample_limit_problem(opt)) {
    print_error("kozu render: --spp: " + *problem);
    return 1;
  }
  const int max_depth = opt.max_depth;
  const Vec2i res = scene->camera.resolution();

  // The film and the output buffers are the render's big allocations: check that they fit first.
  const RenderMemory need = render_memory(res);
  const MemoryLimit limit = memory_limit();
  const double left = static_cast<double>(limit.bytes) - static_cast<double>(current_rss_bytes());
  if (need.total() > left) {
    print_error(fmt::format("{}: a {}x{} render needs about {} (film {}, image buffers {}) but only {} of the {} "
                            "limit ({}) is left; lower the resolution",
                            scene_name, res.x, res.y, format_bytes(need.total()), format_bytes(need.film),
                            format_bytes(need.buffers), format_bytes(std::max(left, 0.0)),
                            format_bytes(static_cast<double>(limit.bytes)), limit.source));
    return 1;
  }

  Film film(res.x, res.y);
  PathIntegrator integrator(*scene, max_depth, opt.direct);
  // From here a stop signal ends sampling, and the images are still written.
  std::optional<ProgressBar> bar;
  if (!args.quiet && isatty(STDERR_FILENO))
    bar.emplace(progress, static_cast<uint64_t>(opt.spp) * res.x * res.y, opt.time_limit);
  const RenderResult result = render(*scene, integrator, film, opt, &progress);
  if (bar) bar->stop();

  // Every output is attempted; failures are reported with what was written.
  std::vector<std::string> written, failures;
  {
    const std::vector<float> rgb = film.rgb();
    for (const auto& o : outputs) {
      if (!o.image) continue;
      try {
        write_image(o.path, res.x, res.y, rgb, flags.tonemap);
        written.push_back(o.path.string());
      } catch (const std::exception& e) {
        failures.push_back(e.what());
      }
    }
  }
  const int signal = StopSignals::received();
  if (!args.stats.empty()) {
    try {
      write_file_atomic(
          args.stats,
          render_stats(*scene, scene_name, opt, max_depth, result, load_seconds, signal, written).dump(2) + "\n");
    } catch (const std::exception& e) {
      failures.push_back(e.what());
    }
  }

  const uint64_t pixels = static_cast<uint64_t>(res.x) * res.y;
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
    std::fprintf(stderr, "kozu: %s%s %dx%d, %.1f spp in %.2f s (%spaths/s, %srays/s, %d threads%s), wrote %s\n",
                 signal ? fmt::format("interrupted by {}: ", StopSignals::name(signal)).c_str() : "",
                 scene_name.c_str(), res.x, res.y, result.film.mean_spp, result.seconds,
                 format_rate(paths_per_second).c_str(), format_rate(rays_per_second).c_str(), result.threads,
                 result.film.discarded_samples
                     ? fmt::format(", {} NaN samples discarded", result.film.discarded_samples).c_str()
                     : "",
                 join(written, "nothing").c_str());
  }
  for (const auto& f : failures) print_error(f);
  if (!failures.empty()) {
    print_error(fmt::format("{} output{} failed; written: {}", failures.size(), failures.size() == 1 ? "" : "s",
                            join(written, "none")));
    return 1;
  }
  // An interrupted render exits as the signal's default action would report it (130, 143, 129).
  return signal ? 128 + signal : 0;
}

}  // namespace

Command add_render_command(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* cmd = app.add_subcommand("render", "Render a scene to EXR/PNG images");
  cmd->add_option("scene", args->scene, "Scene file (JSON, see docs/scene-format.md), or a .gltf/.glb file");
  cmd->add_flag("--demo", args->demo, "Render the built-in demo scene (no files needed)");
  cmd->add_option("-o,--output", args->outputs,
                  "Output image; repeat for several. .exr/.hdr: linear float RGB; .png/.jpg: tone-mapped sRGB "
                  "(default: out/<scene>.exr and out/<scene>.png)");
  cmd->add_option("--spp", args->spp, "Samples per pixel, an integer >= 0 (overrides render.spp; 0 = until the time limit)");
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
  cmd->add_option("--tonemap", args->tonemap, "Display transform for .png/.jpg: aces, neutral or clamp")
      ->capture_default_str();
  cmd->add_option("--exposure", args->exposure,
                  "Exposure in stops applied before the tone map, in [-64, 64] (default 0)");
  cmd->add_flag("-q,--quiet", args->quiet, "No progress bar and no summary line");
  return [args] { return run_render(*args); };
}

}  // namespace kozu::app
