#include "render/job_report.h"

#include "core/memory.h"
#include "core/version.h"
#include "media/medium.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace kozu::render_job {

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

std::string join(const std::vector<std::string>& items, const char* none) {
  std::string s;
  for (const auto& i : items) s += (s.empty() ? "" : ", ") + i;
  return s.empty() ? none : s;
}

Json render_stats(const Scene& scene, const std::string& scene_name, const RenderSettings& opt, int max_depth,
                  const RenderResult& result, double load_seconds, int signal, const std::string& signal_name,
                  const std::vector<std::string>& written) {
  const Vec2i res = scene.camera.resolution();
  const double paths_per_second = result.seconds > 0 ? result.paths / result.seconds : 0.0;
  Json j;
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
  if (signal) j["signal"] = signal_name;
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
  j["tentative_collisions"] = result.rays.tentative_collisions;
  j["tentative_collisions_per_path"] =
      result.paths > 0 ? double(result.rays.tentative_collisions) / double(result.paths) : 0.0;
  j["emission_supersampling"] = {{"planned_spp", result.emission.spp},
                                 {"pixels", result.emission.pixels},
                                 {"samples", result.emission.samples},
                                 {"seconds", result.emission.seconds}};
  j["unsampled_pixels"] = result.film.unsampled_pixels;
  j["nan_pixels"] = result.film.pixels_with_discarded;
  j["nan_samples"] = result.film.discarded_samples;
  j["threads"] = result.threads;
  j["triangles"] = scene.triangle_count();
  j["shapes"] = scene.shapes.size();
  j["lights"] = scene.lights.size();
  j["peak_memory_bytes"] = peak_rss_bytes();
  Json media = Json::object();
  for (const auto& m : scene.media) {
    const Medium::Stats ms = m->stats();
    media[m->name] = {{"voxel_bytes", ms.bytes}, {"majorant_bytes", ms.majorant_bytes}};
    if (ms.lod >= 0) media[m->name]["lod"] = ms.lod;
    if (*ms.lod_mode) media[m->name]["lod_mode"] = ms.lod_mode;
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

ProgressBar::ProgressBar(const RenderProgress& progress, uint64_t total_samples, double time_limit)
    : progress_(progress), total_(total_samples), time_limit_(time_limit), start_(Clock::now()) {
  thread_ = std::thread([this] { run(); });
}

void ProgressBar::stop() {
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

void ProgressBar::run() {
  std::unique_lock lock(mutex_);
  while (!cv_.wait_for(lock, std::chrono::milliseconds(250), [this] { return done_; })) draw();
}

void ProgressBar::draw() {
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

}  // namespace kozu::render_job
