// The inside of a RenderJob (render/job.h), shared by render/job.cpp (planning, loading, the frame loop) and
// render/job_frame.cpp (one frame: pose, film, budget, sampling, writes, report). Not part of the library's API.
#pragma once

#include "core/tonemap.h"
#include "integrators/path.h"
#include "render/aov.h"
#include "render/checkpoint.h"
#include "render/emission_refine.h"
#include "render/guiding_training.h"
#include "render/job.h"
#include "render/job_budget.h"
#include "render/output_paths.h"
#include "render/renderer.h"
#include "scene/animation.h"
#include "scene/render_settings.h"
#include "scene/scene.h"
#include "scene/scene_overrides.h"
#include "textures/texture_cache.h"

#include "core/json_reader.h"
#include "io/image_io.h"

#include <atomic>
#include <chrono>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace kozu {

class BudgetWatch;  // job.cpp

// Now on the steady clock, in nanoseconds (an atomic holds it for RenderJob::fraction_done).
inline int64_t steady_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

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
  DenoiserKind denoiser = DenoiserKind::NlMeans;  // --denoiser
};

struct RenderJob::State {
  using Clock = std::chrono::steady_clock;
  static constexpr int kBudgetSpent = -1;  // render_frame: the budget has no room for this frame

  // One frame being rendered: its settings, outputs, film and what its writes did.
  struct Frame {
    int number = 0;
    RenderSettings opt;
    std::vector<OutputFile> outputs;
    RenderIdentity identity;  // what a checkpoint must match to be continued
    std::vector<Aov> aovs;
    Film film;
    Film::Summary resumed;
    const PathIntegrator* integrator = nullptr;
    std::optional<GuidingTraining> guiding;  // "guiding": "on": the training passes before the frame's samples
    double render_seconds = 0.0, denoise_seconds = 0.0;
    EmissionRefineStats refined;
    // Under --budget the raw images are written first and the denoised ones only when the filter's expected cost
    // and its writes still fit (`denoise_deadline`, seconds since the process started).
    double denoise_deadline = std::numeric_limits<double>::infinity();
    // When the filter itself must stop (what the denoised images' writes need is left after it).
    double filter_deadline = std::numeric_limits<double>::infinity();
    // When sampling was planned to end (seconds since the process started; the budget's plan).
    double sampling_deadline = std::numeric_limits<double>::infinity();
    bool denoise_skipped = false;
    // Partial images and checkpoints between passes.
    int partial_images = 0, checkpoints = 0;
    std::vector<std::string> partial_failures;
    Clock::time_point render_start;
    double next_partial = 0.0, next_checkpoint = 0.0;
  };

  RenderJobSettings args;
  RenderJobHooks hooks;
  Clock::time_point t0;
  std::string scene_name, stem;
  RenderFlags flags;
  std::vector<OutputFile> outputs;
  std::unique_ptr<Scene> scene;
  bool preloaded = false;  // the scene came loaded (RenderJob's second constructor)
  double load_seconds = 0.0;
  RenderSettings opt;  // the scene's settings overridden by the flags, for every frame
  int max_depth = 0;
  Vec2i res{0};
  PixelWindow window;
  bool animated = false, several_frames = false, stats_per_frame = false;
  Vec2i frames{0, 0};
  CameraKey still;
  uint64_t base_scene_hash = 0;
  RenderProgress progress;
  // --budget: the finishing costs (calibrated on the first frame), whether the denoiser fits, the reserve of the
  // current frame and the time the last frame took besides sampling.
  std::optional<render_job::FinishCost> finish_cost;
  bool denoise_planned = false;
  // Under --budget, what ends the process before the budget when loading and the first frame's plan outlast it
  // (job.cpp); released once the first frame's sampling is planned.
  std::shared_ptr<BudgetWatch> start_watch;
  double reserve = 0.0, frame_overhead = 0.0;
  // Under --budget --denoise, the longest time from a frame's planned end of sampling to its denoiser's start (its
  // last samples, the raw writes): the last frame keeps it (plan_budget).
  double denoise_lag = 0.0;
  std::vector<Json> frame_stats;
  std::vector<RenderFrameReport> reports;
  std::vector<std::string> last_written;
  Film last_film;
  Film::Summary last_summary;
  bool frames_done = false;  // the frame loop ended (every output written or reported)
  RenderImages images;       // in memory: the last frame's
  // RenderJob::fraction_done, read from other threads: the frames to render and finished, and the sampling of the
  // current one (its samples to take, the progress counter where it began, its time limit and start).
  std::atomic<int> frame_count{0}, frames_finished{0};
  std::atomic<uint64_t> frame_samples{0}, frame_samples_base{0};
  std::atomic<double> frame_time_limit{0.0};
  std::atomic<int64_t> frame_start_ns{0};

  // The process's place among the ranks, stop signals and messages (through the hooks).
  int rank() const { return hooks.ranks ? hooks.ranks->rank() : 0; }
  int rank_count() const { return hooks.ranks ? hooks.ranks->size() : 1; }
  bool distributed() const { return rank_count() > 1; }
  int stop_signal() const { return hooks.stop_signal ? hooks.stop_signal() : 0; }
  std::string signal_name(int signal) const;
  void print_error(const std::string& message) const;
  bool denoising() const { return args.denoise || args.denoise_only; }

  // render/job.cpp: the phases before the frames, each false with its message printed.
  int run();
  bool plan_outputs();
  bool check_scene_kind() const;
  TextureCacheOptions texture_options() const;  // the texture cache of the load: its memory and folder
  bool load();
  bool apply_settings();
  bool check_memory() const;
  bool plan_frames();
  uint64_t fingerprint() const;
  std::vector<OutputFile> frame_outputs(int frame) const;
  int run_frames();

  // render/job_frame.cpp: one frame (a still is frame 0 of one), rendered and written; its exit status or
  // kBudgetSpent.
  int render_frame(int frame, int frames_left);
  bool pose_frame(Frame& f);
  bool open_film(Frame& f);
  int plan_budget(Frame& f, int frames_left);
  PassHook pass_hook(Frame& f);
  ImageExtras image_extras(const Frame& f, bool partial) const;
  void write_images(Frame& f, bool partial, std::vector<std::string>& written, std::vector<std::string>& failures);
  std::vector<float> denoised_image(Frame& f);
  void keep_images(Frame& f);
  void clamp_negative(const Frame& f, std::vector<float>& pixels) const;
  void write_frame_stats(Frame& f, const RenderResult& result, int signal, Clock::time_point finish_start,
                         const std::vector<std::string>& written, std::vector<std::string>& failures);
  void report_frame(const Frame& f, const RenderResult& result, int signal, const std::vector<std::string>& written,
                    const std::vector<std::string>& failures) const;
};

// Under MPI the ranks pass together every point before which one of them could fail alone (RankGroup::agree): a
// rank that returns early with an error still takes part (from the destructor), so the others stop with it instead
// of waiting for it in the film's reduction, and ranks started with different settings are caught before they
// render. On one process it does nothing.
class RankGate {
 public:
  RankGate(const RenderJob::State& job, std::string what) : job_(job), what_(std::move(what)) {}
  ~RankGate() {
    if (!passed_) pass(1, 0);
  }
  RankGate(const RankGate&) = delete;
  RankGate& operator=(const RankGate&) = delete;
  // True when every rank is ready with the same fingerprint; otherwise rank 0 names the rank that is not.
  bool pass(int status, uint64_t fingerprint);

 private:
  const RenderJob::State& job_;
  std::string what_;
  bool passed_ = false;
};

}  // namespace kozu
