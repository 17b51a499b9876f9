// What a render job (render/job.h) tells its user: the progress bar on stderr while it samples, rates and durations
// in the summary line, and the statistics written with --stats.
#pragma once

#include "core/json_reader.h"
#include "render/renderer.h"
#include "scene/render_settings.h"
#include "scene/scene.h"

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace kozu::render_job {

std::string format_duration(double s);       // "01:05", "1:02:03", "--:--"
std::string format_rate(double per_second);  // "1.25 M"
// The items joined with ", ", or `none` for none.
std::string join(const std::vector<std::string>& items, const char* none);

// The statistics of one rendered frame (docs/production.md lists the keys); `signal_name` is the stop signal's
// ("SIGTERM") when `signal` is not 0.
Json render_stats(const Scene& scene, const std::string& scene_name, const RenderSettings& opt, int max_depth,
                  const RenderResult& result, double load_seconds, int signal, const std::string& signal_name,
                  const std::vector<std::string>& written);

// Draws a progress bar on stderr until stopped.
class ProgressBar {
 public:
  ProgressBar(const RenderProgress& progress, uint64_t total_samples, double time_limit);
  ~ProgressBar() { stop(); }
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;
  void stop();

 private:
  using Clock = std::chrono::steady_clock;
  void run();
  void draw();

  const RenderProgress& progress_;
  uint64_t total_;
  double time_limit_;
  Clock::time_point start_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool done_ = false;
  std::thread thread_;
};

}  // namespace kozu::render_job
