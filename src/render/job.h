// A render job: what `kozu render` does between parsing its flags and exiting, as a library call (the command in
// apps/render_command.cpp parses the flags, installs the signal handlers, starts MPI and runs one). From the
// settings (the flags as given, validated here by the rules their scene keys use) it plans and checks every output
// before loading anything, loads the scene, checks the outputs against the scene's inputs, renders the frames (a
// still is frame 0 of one) and writes them: the images (with AOVs and alpha), the denoised images, partial images and
// checkpoints between passes, the statistics; under --budget it reserves the time the writes need
// (render/job_budget.h). Messages, warnings and the progress bar go to stderr as the command prints them.
//
// What the job needs from its process comes through RenderJobHooks, so src/ knows neither MPI nor signals: the
// ranks sharing the render (RankGroup: agreement before rendering, the film's reduction), the first stop signal
// received and its name, and the cooperative section during which a stop signal ends sampling instead of the process.
#pragma once

#include "integrators/integrator.h"
#include "render/film.h"

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace kozu {

class Scene;
class RankGate;

// The flags of a render, as given (numbers as text: the job validates them, and reports a bad value the way the
// command always has).
struct RenderJobSettings {
  std::string scene;  // a scene file (.json, .gltf, .glb); empty with `demo`
  bool demo = false;
  std::vector<std::string> outputs;  // -o; none: out/<scene>.exr and .png
  std::optional<std::string> spp, time_limit, threads, seed, resolution, max_depth, exposure, texture_cache_mb;
  std::string stats;  // --stats FILE
  bool quiet = false;
  std::string tonemap = "aces";
  std::optional<std::string> direct;
  // Production (docs/production.md).
  std::optional<std::string> budget, partial_every, checkpoint_every, crop, sample_range, aov, frames;
  std::string checkpoint, resume;
  bool denoise = false, denoise_only = false;
  std::optional<std::string> denoiser;  // --denoiser: "nlmeans" (default), "regression", "unet" or "ensemble"
  bool alpha = false;                    // an A channel in the EXRs
  std::vector<std::string> defines;      // -D PATH=VALUE
  std::vector<std::string> empty_flags;  // file flags given an empty name (--stats ''), refused
  // In memory (the Python module): no file is written and no output, --stats or --checkpoint may be given; the last
  // frame's images stay in the job (RenderJob::images()).
  bool in_memory = false;
  // The scene's JSON when it has no file (a scene given as text or a Python dict): its identity in the images'
  // attributes, in place of the file's bytes.
  std::string scene_text;
};

// What --demo and --demo-animation mean when the command line leaves them open (`kozu render`): the still, 1920 x 1080
// within --budget 123 (camp 6's limit) with --denoise --denoiser ensemble; the animation, the demo's camera move at
// 640 x 360 within --budget 256 (camp 10's) with --denoise. Any of --spp, --time-limit, --budget, --resume or
// --sample-range leaves the budget and the denoiser to the user; a --denoiser given is kept.
void apply_demo_defaults(RenderJobSettings& args, bool animation);

// The images of a frame rendered in memory (RenderJobSettings::in_memory): what the outputs would hold.
struct RenderImages {
  int width = 0, height = 0;
  std::vector<float> rgb;             // linear RGB, rows top first: the EXR's pixels
  std::vector<float> denoised;        // with --denoise
  std::vector<std::string> channels;  // the EXR's other channels: "A" (--alpha), the AOVs' ("albedo.R", "Z", ...)
  std::vector<float> data;            // channels.size() values per pixel
  // The channels grouped, in their order: "alpha" (1 channel) with --alpha, then each AOV's name and channel count.
  std::vector<std::pair<std::string, int>> layers;
};

// The processes that share a render (MPI ranks; see apps/mpi_world.h for the one the command supplies).
class RankGroup {
 public:
  virtual ~RankGroup() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  // Collective: the worst status over the ranks and the lowest rank that has it, and the first rank whose
  // fingerprint differs from rank 0's (-1: none).
  struct Agreement {
    int status = 0, failed_rank = -1, mismatched_rank = -1;
    bool ok() const { return status == 0 && mismatched_rank < 0; }
  };
  virtual Agreement agree(int status, uint64_t fingerprint) const = 0;
  // Sums every rank's film and counters onto rank 0's; false (with a message) on failure.
  virtual bool reduce(Film& film, RayCounters& rays, uint64_t& paths) const = 0;
  virtual double max(double x) const = 0;  // the largest x over the ranks, on every rank
};

struct RenderJobHooks {
  const RankGroup* ranks = nullptr;             // null: this process alone
  std::function<int()> stop_signal;             // the first stop signal received (0: none); unset: never
  std::function<std::string(int)> signal_name;  // "SIGTERM"; unset: "signal N"
  // Called once sampling may begin: while the returned object lives, a stop signal raises `cancel` (which ends
  // sampling; the images of the samples taken are still written) instead of ending the process.
  std::function<std::shared_ptr<void>(std::atomic<bool>& cancel)> cooperative;
  // A failure's message (the job then returns 1); unset: printed on stderr as "error: MESSAGE".
  std::function<void(const std::string&)> error;
};

// One frame the job rendered (or tried to).
struct RenderFrameReport {
  int frame = 0;
  int status = 0;                    // 0, 1 (a failure, reported), 128 + a stop signal
  std::vector<std::string> written;  // the files written: images and the checkpoint
  Film::Summary film;                // its samples (rank 0's: the whole image)
};

class RenderJob {
 public:
  // A job that loads settings.scene (or the demo) itself, after checking its outputs.
  RenderJob(RenderJobSettings settings, RenderJobHooks hooks = {});
  // A job for a scene loaded already (scene/scene_loader.h): settings.scene names its file, for messages and the
  // checkpoints' identity (empty with settings.demo); overrides (-D) and the texture cache's size act on loading, so
  // settings.defines is refused and texture_cache_mb unused.
  RenderJob(std::unique_ptr<Scene> scene, RenderJobSettings settings, RenderJobHooks hooks = {});
  ~RenderJob();
  RenderJob(const RenderJob&) = delete;
  RenderJob& operator=(const RenderJob&) = delete;

  // Runs the whole job: the exit status of `kozu render` (0; 1 for bad input or a failed write, the message printed;
  // 128 + a stop signal).
  int run();

  const std::vector<RenderFrameReport>& frames() const;  // in order
  const Film& film() const;                              // the last frame's film (on rank 0 the whole image's)
  const Scene* scene() const;                            // once loaded
  const RenderImages& images() const;                    // the last frame's, with settings.in_memory
  // From any thread while run() runs: the fraction of the frames' samples taken so far (of the time limit's time,
  // when that ends sampling first), and a request to stop sampling (the images of the samples taken are kept).
  double fraction_done() const;
  void cancel();
  // Everything is on disk: whether the process may skip the scene's teardown (under --budget, not under MPI).
  bool exit_without_teardown() const;

 private:
  friend class RankGate;  // render/job_state.h
  struct State;
  std::unique_ptr<State> s_;
};

}  // namespace kozu
