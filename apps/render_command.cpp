// `kozu render`: the command line of a render job (render/job.h). It parses the flags, and supplies what the job
// needs from the process: the MPI ranks (apps/mpi_world.h) and the stop signals (apps/stop_signals.h: during
// sampling the first one ends sampling, and the images of the samples taken are still written).
#include "apps/commands.h"
#include "apps/stop_signals.h"
#include "core/file_io.h"
#include "core/json_reader.h"
#ifdef KOZU_HAVE_MPI
#include "apps/mpi_world.h"
#endif
#include "render/job.h"
#include "scene/scene_loader.h"
#include "scene/scene_overrides.h"

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace kozu::app {

namespace {

#ifdef KOZU_HAVE_MPI
// The job's view of the MPI world.
class MpiRanks final : public RankGroup {
 public:
  explicit MpiRanks(const MpiWorld& world) : world_(world) {}
  int rank() const override { return world_.rank(); }
  int size() const override { return world_.size(); }
  Agreement agree(int status, uint64_t fingerprint) const override {
    const MpiWorld::Agreement a = world_.agree(status, fingerprint);
    return {a.status, a.failed_rank, a.mismatched_rank};
  }
  bool reduce(Film& film, RayCounters& rays, uint64_t& paths) const override {
    return world_.reduce(film, rays, paths);
  }
  double max(double x) const override { return world_.max(x); }

 private:
  const MpiWorld& world_;
};
#endif

// --print-scene: the scene's JSON (the built-in demo's, or the file's) with the -D overrides applied.
int print_scene(const RenderJobSettings& args) {
  try {
    const std::string name = args.demo ? "<demo>" : args.scene;
    if (args.demo == !args.scene.empty())
      throw std::runtime_error("kozu render --print-scene: give a scene file or --demo");
    const std::string text = args.demo ? std::string(demo_scene_json()) : read_input_file(args.scene);
    Json root = parse_json_text(text, name);  // checked even when printed as it is
    std::vector<SceneOverride> overrides;
    for (const std::string& d : args.defines) overrides.push_back(parse_scene_override(d));
    apply_scene_overrides(root, overrides, name);
    // Without overrides the file as written (its key order and comments' place), else the edited tree.
    std::printf("%s\n", overrides.empty() ? text.c_str() : root.dump(1).c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}

// The ffmpeg command that makes a video of the frames --demo-animation wrote (the denoised ones when the first
// frame has one: under a budget the denoiser runs only where it fits).
void print_video_hint(const RenderJobSettings& args) {
  std::string pattern = "out/demo/%04d.png";
  for (const std::string& o : args.outputs)
    if (o.size() > 4 && o.compare(o.size() - 4, 4, ".png") == 0) pattern = o;
  std::string denoised = pattern;
  denoised.insert(denoised.size() - 4, ".denoised");
  std::string first = denoised;
  if (const size_t at = first.find("%04d"); at != std::string::npos) first.replace(at, 4, "0000");
  std::error_code ec;
  if (args.denoise && std::filesystem::exists(first, ec)) pattern = denoised;
  std::fprintf(
      stderr,
      "kozu: make the video with: ffmpeg -framerate 24 -i '%s' -c:v libx264 -pix_fmt yuv420p -crf 18 demo.mp4\n",
      pattern.c_str());
}

// `done` runs once the job has finished (before a fast exit skips the teardown).
int run_render(const RenderJobSettings& args, const std::function<void(int)>& done) {
  RenderJobHooks hooks;
#ifdef KOZU_HAVE_MPI
  std::optional<MpiRanks> ranks;
  if (const MpiWorld* world = MpiWorld::instance()) hooks.ranks = &ranks.emplace(*world);
#endif
  hooks.stop_signal = [] { return StopSignals::received(); };
  hooks.signal_name = [](int signal) { return std::string(StopSignals::name(signal)); };
  hooks.cooperative = [](std::atomic<bool>& cancel) -> std::shared_ptr<void> {
    return std::make_shared<StopSignals::Cooperative>(cancel);
  };
  RenderJob job(args, hooks);
  const int status = job.run();
  done(status);
  if (job.exit_without_teardown()) {
    // Everything is on disk: under a budget the scene's teardown (a large BVH, the texture cache) is skipped (not
    // under MPI, which must be finalized).
    std::fflush(nullptr);
    std::_Exit(status);
  }
  return status;
}

}  // namespace

Command add_render_command(CLI::App& app) {
  auto args = std::make_shared<RenderJobSettings>();
  CLI::App* cmd = app.add_subcommand("render", "Render a scene to EXR/PNG images");
  cmd->add_option("scene", args->scene, "Scene file (JSON, see docs/scene-format.md), or a .gltf/.glb file");
  cmd->add_flag("--demo", args->demo,
                "Render the built-in demo scene (no files needed): by default 1920x1080 within --budget 123 (the "
                "Raytracing camp's limit, from the process's start) with --denoise --denoiser ensemble");
  auto demo_animation = std::make_shared<bool>(false);
  auto print_scene_flag = std::make_shared<bool>(false);
  cmd->add_flag("--demo-animation", *demo_animation,
                "Render the demo's camera move (24 frames, 24 fps) as numbered images (default out/demo/%04d.png, "
                "640x360) within --budget 256 for the whole sequence, denoised, and print the ffmpeg command for the "
                "video");
  cmd->add_flag("--print-scene", *print_scene_flag,
                "Print the scene (--demo's, or the file's) as JSON with the -D overrides applied, and exit: the "
                "starting point for a scene of your own");
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
                  "Direct light from quad/polygon lights: ltc (the default: closed form as a control variate of "
                  "stochastic shadows, unbiased; sample under guiding), sample, ltc-ratio (Heitz et al. 2018, biased) "
                  "or ltc-preview (closed form, no shadows) (overrides render.direct)");
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
  cmd->add_option("--denoiser", args->denoiser,
                  "The filter of --denoise: nlmeans (feature-guided non-local means, the default), regression "
                  "(first-order feature regression: smoother on flat walls, more residual noise), unet (a small U-Net "
                  "trained on kozu's own renders, run with oneDNN) or ensemble (nlmeans and regression weighed by "
                  "their estimated errors: lower error where they differ, twice the time); docs/production.md");
  cmd->add_option("--frames", args->frames,
                  "Frames of the scene's animation to render: A:B (both included) or N (outputs need a %04d pattern)");
  cmd->add_option("--aov", args->aov,
                  "Extra EXR channels: a comma list of albedo, normal, depth, position, variance, sample_count, emission");
  cmd->add_flag("--alpha", args->alpha,
                "Write coverage as an A channel in the EXRs (the fraction of each pixel's camera samples that hit "
                "geometry); .exr outputs only");
  cmd->add_option("--sample-range", args->sample_range,
                  "Render samples A..B-1 of every pixel: A:B (parts of disjoint ranges combine with kozu merge)");
  return [args, cmd, demo_animation, print_scene_flag] {
    for (const char* flag : {"--stats", "--checkpoint", "--resume", "--output"})
      if (cmd->count(flag) > 0)
        for (const std::string& v : cmd->get_option(flag)->as<std::vector<std::string>>())
          if (v.empty()) args->empty_flags.push_back(std::string(flag) == "--output" ? "-o" : flag);
    if (*demo_animation && !args->scene.empty()) {
      std::fprintf(stderr, "error: kozu render: --demo-animation renders the built-in scene: give no scene file\n");
      return 1;
    }
    if (*print_scene_flag) return print_scene(*args);
    apply_demo_defaults(*args, *demo_animation);
    return run_render(*args, [&](int status) {
      if (status == 0 && *demo_animation && !args->quiet) print_video_hint(*args);
    });
  };
}

}  // namespace kozu::app
