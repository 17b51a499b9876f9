// `kozu render`: load a scene, render it progressively, write images and statistics.
#include "apps/commands.h"
#include "core/error.h"
#include "core/version.h"
#include "integrators/path.h"
#include "io/image_io.h"
#include "io/scene_loader.h"
#include "io/stats.h"
#include "media/medium.h"
#include "render/renderer.h"

#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <mutex>
#include <thread>

namespace kozu::app {

namespace {

struct RenderArgs {
  std::string scene;
  bool demo = false;
  std::vector<std::string> outputs;
  std::optional<int> spp;
  std::optional<double> time_limit;
  int threads = 0;
  std::optional<uint64_t> seed;
  std::string resolution;
  std::optional<int> max_depth;
  std::string stats;
  bool quiet = false;
  std::string tonemap = "aces";
  float exposure = 0.0f;
};

RenderProgress* g_progress = nullptr;

extern "C" void on_sigint(int) {
  // First Ctrl-C: stop sampling and write what is done. Second: default action (terminate).
  if (g_progress) g_progress->cancel.store(true);
  std::signal(SIGINT, SIG_DFL);
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

Vec2i parse_resolution(const std::string& s) {
  int w = 0, h = 0;
  char x = 0, extra = 0;
  if (std::sscanf(s.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X') || w < 1 || h < 1 ||
      w > 65536 || h > 65536)
    throw std::invalid_argument(fmt::format("--resolution: expected WIDTHxHEIGHT (e.g. 1920x1080), got '{}'", s));
  return Vec2i(w, h);
}

int run_render(const RenderArgs& args) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  if (args.demo == !args.scene.empty()) {
    std::fprintf(stderr, "kozu render: give a scene file or --demo (not both)\n");
    return 1;
  }
  // Validate everything about the command line before loading anything.
  std::vector<std::filesystem::path> outputs;
  for (const auto& o : args.outputs) outputs.emplace_back(o);
  const std::string stem = args.demo ? "demo" : std::filesystem::path(args.scene).stem().string();
  if (outputs.empty()) {
    outputs = {std::filesystem::path("out") / (stem + ".exr"), std::filesystem::path("out") / (stem + ".png")};
  }
  ToneMap tonemap;
  try {
    for (const auto& o : outputs)
      if (!is_supported_output(o))
        throw std::invalid_argument(
            fmt::format("{}: unsupported output format (use .exr, .hdr, .png or .jpg)", o.string()));
    tonemap.curve = ToneMap::parse(args.tonemap);
    if (!args.resolution.empty()) parse_resolution(args.resolution);
    tonemap.exposure = args.exposure;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "kozu render: %s\n", e.what());
    return 1;
  }

  std::unique_ptr<Scene> scene;
  try {
    scene = args.demo ? load_demo_scene() : load_scene_file(args.scene);
    if (!args.resolution.empty()) {
      scene->camera.set_resolution(parse_resolution(args.resolution));
      scene->set_media_view();
    }
  } catch (const InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s: %s\n", args.demo ? "<demo>" : args.scene.c_str(), e.what());
    return 1;
  }
  const double load_seconds = std::chrono::duration<double>(Clock::now() - t0).count();

  RenderOptions opt;
  // --time-limit alone asks for "as many samples as fit": it lifts the scene's sample cap.
  opt.spp = args.spp.value_or(args.time_limit && *args.time_limit > 0.0 ? 0 : scene->settings.spp);
  opt.time_limit = args.time_limit.value_or(scene->settings.time_limit);
  opt.threads = args.threads;
  opt.seed = args.seed.value_or(scene->settings.seed);
  opt.filter = scene->settings.filter;
  if (opt.spp == 0 && opt.time_limit <= 0.0) {
    std::fprintf(stderr, "kozu render: --spp 0 (no sample limit) needs a time limit\n");
    return 1;
  }
  const int max_depth = args.max_depth.value_or(scene->settings.max_depth);
  const Vec2i res = scene->camera.resolution();

  Film film(res.x, res.y);
  PathIntegrator integrator(*scene, max_depth);
  RenderProgress progress;
  g_progress = &progress;
  std::signal(SIGINT, on_sigint);
  std::optional<ProgressBar> bar;
  const bool interactive = !args.quiet && isatty(STDERR_FILENO);
  if (interactive) bar.emplace(progress, static_cast<uint64_t>(opt.spp) * res.x * res.y, opt.time_limit);
  const RenderResult result = render(*scene, integrator, film, opt, &progress);
  if (bar) bar->stop();
  std::signal(SIGINT, SIG_DFL);
  g_progress = nullptr;
  const bool interrupted = progress.cancel.load();

  const std::vector<float> rgb = film.rgb();
  std::vector<std::string> written;
  try {
    for (const auto& o : outputs) {
      write_image(o, res.x, res.y, rgb, tonemap);
      written.push_back(o.string());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }

  const double paths_per_second = result.seconds > 0 ? result.paths / result.seconds : 0.0;
  const double rays_per_second = result.seconds > 0 ? result.rays.total() / result.seconds : 0.0;
  if (!args.stats.empty()) {
    nlohmann::json j;
    j["kozu_version"] = KOZU_VERSION;
    j["scene"] = args.demo ? "<demo>" : args.scene;
    j["resolution"] = {res.x, res.y};
    j["spp"] = result.film.mean_spp;
    j["spp_min"] = result.film.min_spp;
    j["spp_max"] = result.film.max_spp;
    j["spp_target"] = opt.spp;
    j["max_depth"] = max_depth;
    j["seed"] = opt.seed;
    j["time_limit"] = opt.time_limit;
    j["hit_time_limit"] = result.hit_time_limit;
    j["interrupted"] = interrupted;
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
    j["rays_per_second"] = rays_per_second;
    j["nan_pixels"] = result.film.pixels_with_discarded;
    j["nan_samples"] = result.film.discarded_samples;
    j["threads"] = result.threads;
    j["triangles"] = scene->triangle_count();
    j["shapes"] = scene->shapes.size();
    j["lights"] = scene->lights.size();
    j["peak_memory_bytes"] = peak_rss_bytes();
    nlohmann::json media = nlohmann::json::object();
    for (const auto& m : scene->media) {
      const Medium::Stats ms = m->stats();
      media[m->name] = {{"voxel_bytes", ms.bytes}};
      if (ms.lod >= 0) media[m->name]["lod"] = ms.lod;
    }
    j["media"] = media;
    j["outputs"] = written;
    try {
      write_json_file(args.stats, j);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "error: %s\n", e.what());
      return 1;
    }
  }
  if (!args.quiet) {
    std::string files;
    for (const auto& w : written) files += (files.empty() ? "" : ", ") + w;
    std::fprintf(stderr, "kozu: %s%s %dx%d, %.1f spp in %.2f s (%spaths/s, %srays/s, %d threads%s), wrote %s\n",
                 interrupted ? "interrupted " : "", args.demo ? "<demo>" : args.scene.c_str(), res.x, res.y,
                 result.film.mean_spp, result.seconds, format_rate(paths_per_second).c_str(),
                 format_rate(rays_per_second).c_str(), result.threads,
                 result.film.discarded_samples
                     ? fmt::format(", {} NaN samples discarded", result.film.discarded_samples).c_str()
                     : "",
                 files.c_str());
  }
  return 0;
}

}  // namespace

Command add_render_command(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* cmd = app.add_subcommand("render", "Render a scene to EXR/PNG images");
  cmd->add_option("scene", args->scene, "Scene file (JSON, see docs/scene-format.md)");
  cmd->add_flag("--demo", args->demo, "Render the built-in demo scene (no files needed)");
  cmd->add_option("-o,--output", args->outputs,
                  "Output image; repeat for several. .exr/.hdr: linear float RGB; .png/.jpg: tone-mapped sRGB "
                  "(default: out/<scene>.exr and out/<scene>.png)");
  cmd->add_option("--spp", args->spp, "Samples per pixel (overrides render.spp; 0 = until the time limit)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--time-limit", args->time_limit,
                  "Stop sampling after this many seconds (loading excluded); without --spp, samples until then")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--threads", args->threads, "Worker threads (default: all cores)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--seed", args->seed, "Random seed (overrides render.seed)");
  cmd->add_option("--resolution", args->resolution, "Image size WIDTHxHEIGHT (overrides camera.resolution)");
  cmd->add_option("--max-depth", args->max_depth, "Maximum path length in bounces (overrides render.max_depth)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--stats", args->stats, "Write render statistics as JSON to this file");
  cmd->add_option("--tonemap", args->tonemap, "Display transform for .png/.jpg: aces, neutral or clamp")
      ->capture_default_str();
  cmd->add_option("--exposure", args->exposure, "Exposure in stops applied before the tone map")->capture_default_str();
  cmd->add_flag("-q,--quiet", args->quiet, "No progress bar and no summary line");
  return [args] { return run_render(*args); };
}

}  // namespace kozu::app
