#include "render/job.h"

#include "core/error.h"
#include "core/file_io.h"
#include "core/memory.h"
#include "core/process_clock.h"
#include "core/temp_files.h"
#include "io/checkpoint_file.h"
#include "io/image_io.h"
#include "render/job_outputs.h"
#include "render/job_state.h"
#include "render/learned_denoiser.h"
#include "scene/scene_loader.h"
#include "textures/texture_cache.h"

#include <fmt/format.h>

#include <algorithm>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <thread>

#include <unistd.h>

namespace kozu {

using namespace render_job;

namespace {

RenderFlags validate_flags(const RenderJobSettings& args) {
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
  if (args.denoiser) {
    const std::optional<DenoiserKind> kind = parse_denoiser_kind(*args.denoiser);
    if (!kind)
      throw InputError("kozu render", "--denoiser", fmt::format("'{}': expected {}", *args.denoiser, kDenoiserNames));
    if (!args.denoise && !args.denoise_only)
      throw InputError("kozu render", "--denoiser", "chooses the filter of --denoise or --denoise-only: give one");
    f.denoiser = *kind;
    // Before anything is rendered: a build without the trained weights cannot run the network.
    if (f.denoiser == DenoiserKind::Unet) try {
        builtin_unet_weights();
      } catch (const std::runtime_error& e) {
        throw InputError("kozu render", "--denoiser", e.what());
      }
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
// AOVs add the feature sums (with, at worst, the visible emission's in every pixel and the positions) and, for the
// EXR, their channels twice (the values and the interleaved copy). The visible emission supersampled apart
// (render/emission_supersampling.h) keeps a byte a pixel and at most 1/32 of the pixels' estimates (under 2 bytes
// a pixel in all); its pilot's 24 bytes a pixel are freed before the render, below the output buffers' share.
// "direct": "ltc" keeps each pixel's memory beside the film (PixelMemory).
RenderMemory render_memory(Vec2i res, bool aovs, bool pixel_memory) {
  const double pixels = static_cast<double>(res.x) * res.y;
  constexpr size_t kFeatures = sizeof(Film::FeaturePixel) + sizeof(EmissionSums::Pixel) + sizeof(Vec3);
  constexpr double kApart = 1.0 + static_cast<double>(sizeof(ApartEmission)) / 32.0;
  const size_t memory = pixel_memory ? sizeof(PixelMemory) : 0;
  return {pixels * (static_cast<double>(Film::bytes_per_pixel() + (aovs ? kFeatures : 0) + memory) + kApart),
          pixels * (12.0 + 12.0 + 22.0 + 3.0 + (aovs ? 2.0 * 4.0 * 17.0 : 0.0))};
}

// The scene a checkpoint belongs to: the scene file's bytes, each input file's name and size (hashing every
// texture's bytes would cost seconds; a file replaced by one of another size is caught) and the bytes of the scene
// files it includes.
uint64_t scene_hash(const RenderJobSettings& args, const Scene& scene) {
  const std::string text = args.demo                  ? std::string("kozu built-in demo scene")
                           : !args.scene_text.empty() ? args.scene_text
                                                      : read_input_file(args.scene);
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

}  // namespace

std::string RenderJob::State::signal_name(int signal) const {
  return hooks.signal_name ? hooks.signal_name(signal) : fmt::format("signal {}", signal);
}

// Errors name the rank under MPI: every rank loads and checks for itself.
void RenderJob::State::print_error(const std::string& message) const {
  if (hooks.error)
    hooks.error(distributed() ? fmt::format("rank {}: {}", rank(), message) : message);
  else if (distributed())
    std::fprintf(stderr, "error: rank %d: %s\n", rank(), message.c_str());
  else
    std::fprintf(stderr, "error: %s\n", message.c_str());
}

bool RankGate::pass(int status, uint64_t fingerprint) {
  passed_ = true;
  const RankGroup* ranks = job_.hooks.ranks;
  if (!ranks || ranks->size() <= 1) return status == 0;
  const RankGroup::Agreement a = ranks->agree(status, fingerprint);
  if (a.ok()) return true;
  if (ranks->rank() == 0 && status == 0) {
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
}

// The outputs from the flags (the default ones, the denoised ones, the statistics and the checkpoint), checked for
// what the flags ask of them.
bool RenderJob::State::plan_outputs() {
  if (args.in_memory) {
    if (!args.outputs.empty() || !args.stats.empty() || !args.checkpoint.empty()) {
      print_error("kozu render: a render in memory writes no files (-o, --stats, --checkpoint)");
      return false;
    }
    return true;
  }
  for (const auto& o : args.outputs) outputs.push_back({o, "-o", true});
  stem = args.demo ? "demo" : std::filesystem::path(args.scene).stem().string();
  if (outputs.empty()) {
    outputs = {{std::filesystem::path("out") / (stem + ".exr"), "-o", true},
               {std::filesystem::path("out") / (stem + ".png"), "-o", true}};
  }
  if (!args.stats.empty()) outputs.push_back({args.stats, "--stats", false});
  if (denoising()) {
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
        return false;
      }
  if (args.aov && std::none_of(outputs.begin(), outputs.end(),
                               [](const OutputFile& o) { return o.image && lower_extension(o.path) == ".exr"; })) {
    print_error("kozu render: --aov: AOVs are extra channels of .exr outputs, and no output is one; add -o NAME.exr");
    return false;
  }
  return true;
}

// Files that are not scenes: said so, not answered with a JSON syntax error.
bool RenderJob::State::check_scene_kind() const {
  if (args.demo) return true;
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
    why =
        fmt::format("kozu reads kozu scene files (.json) and glTF 2.0 (.gltf, .glb), not {}: convert it to glTF", ext);
  else if (is_supported_output(args.scene) || ext == ".tx" || ext == ".tif" || ext == ".tiff")
    why = "an image is not a scene: give a scene file (.json) or a .gltf/.glb";
  if (why.empty()) return true;
  print_error(fmt::format("{}: {}", args.scene, why));
  return false;
}

// Images that are not tiled mip-mapped textures are converted once into a folder beside the first output.
TextureCacheOptions RenderJob::State::texture_options() const {
  TextureCacheOptions t;
  t.memory_mb = flags.texture_cache_mb;
  if (!outputs.empty()) t.convert_dir = outputs.front().path.parent_path() / ".kozu-tx";
  return t;
}

bool RenderJob::State::load() {
  try {
    if (!preloaded) {
      SceneLoadOptions load;
      load.textures = texture_options();
      load.overrides = flags.overrides;
      // A .gltf or .glb file is a scene of its own (its camera, lights or a default environment).
      const std::string ext = args.demo ? "" : lower_extension(args.scene);
      scene = args.demo                         ? load_demo_scene(load)
              : ext == ".gltf" || ext == ".glb" ? load_gltf_file(args.scene, load)
                                                : load_scene_file(args.scene, load);
    }
    if (flags.resolution) {
      scene->camera.set_resolution(*flags.resolution);
      scene->set_media_view();
    }
    for (const std::string& w : scene->all_warnings()) std::fprintf(stderr, "warning: %s\n", w.c_str());
    check_outputs(outputs, scene->input_files);
  } catch (const InputError& e) {
    print_error(e.what() + override_note(flags.overrides, e.json_path()));
    return false;
  } catch (const std::bad_alloc&) {
    print_error(scene_name + ": out of memory while loading the scene");
    return false;
  } catch (const std::exception& e) {
    print_error(scene_name + ": " + e.what());
    return false;
  }
  return true;
}

// The scene's settings, overridden by the flags; the window and the ranks' share.
bool RenderJob::State::apply_settings() {
  opt = scene->settings;
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
    return false;
  }
  max_depth = opt.max_depth;
  res = scene->camera.resolution();
  // Under mpirun every rank renders its share of the tiles; rank 0 gathers the film and writes the outputs.
  opt.tile_rank = rank();
  opt.tile_ranks = rank_count();
  // A checkpoint holds the film's sums, not which pixels took their samples without the visible emission: renders
  // that write or resume one keep the emission in every sample (render/emission_supersampling.h). MPI ranks each
  // make the same choice over the whole window (it is deterministic), so rank 0's film adds it back.
  if (!args.checkpoint.empty() || !args.resume.empty()) opt.emission_supersampling = false;
  // Without a sample count the choice is planned from the pilot's time, which differs between ranks.
  if (distributed() && opt.spp <= 0) opt.emission_supersampling = false;
  if (distributed() && (flags.partial_every || flags.checkpoint_every)) {
    print_error(
        "kozu render: --partial-every and --checkpoint-every are not supported across MPI ranks (each rank "
        "holds only its tiles until the end); the final images and --checkpoint are");
    return false;
  }
  window = PixelWindow{Vec2i(0), res};
  if (args.crop) {
    try {
      window = crop_flag(*args.crop, res);
    } catch (const InputError& e) {
      print_error(e.what());
      return false;
    }
  }
  return true;
}

// The film and the output buffers are the render's big allocations: check that they fit first.
bool RenderJob::State::check_memory() const {
  const RenderMemory need = render_memory(window.size, !flags.aovs.empty() || flags.sample_range || args.crop,
                                          opt.direct == DirectLighting::Ltc);
  const MemoryLimit limit = memory_limit();
  const double left = memory_left(limit);
  if (need.total() <= left) return true;
  print_error(
      fmt::format("{}: a {}x{} render needs about {} (film {}, image buffers {}) but only {} of the {} "
                  "limit ({}) is left; lower the resolution",
                  scene_name, window.size.x, window.size.y, format_bytes(need.total()), format_bytes(need.film),
                  format_bytes(need.buffers), format_bytes(std::max(left, 0.0)),
                  format_bytes(static_cast<double>(limit.bytes)), limit.source));
  return false;
}

std::vector<OutputFile> RenderJob::State::frame_outputs(int frame) const {
  std::vector<OutputFile> out = outputs;
  for (auto& o : out) o.path = frame_path(o.path.string(), frame);
  return out;
}

// Animation: the frames to render and each one's output names.
bool RenderJob::State::plan_frames() {
  animated = scene->animation.animated();
  if (args.frames && !animated) {
    print_error(
        fmt::format("kozu render: --frames: {} has no \"animation\" block (docs/production.md#animation)", scene_name));
    return false;
  }
  if (animated) {
    frames = Vec2i(0, scene->animation.frames - 1);
    if (args.frames) {
      try {
        frames = frames_flag(*args.frames, scene->animation.frames);
      } catch (const InputError& e) {
        print_error(e.what());
        return false;
      }
    }
  }
  several_frames = frames.y > frames.x;
  stats_per_frame = !args.stats.empty() && has_frame_pattern(args.stats);
  if (several_frames && args.outputs.empty()) {
    // The default outputs of an animation: out/<scene>/0000.exr and .png, ... (with --denoise also
    // 0000.denoised.exr and .png; --denoise-only writes the denoised image under the plain names).
    for (auto& o : outputs)
      if (o.image)
        o.path = o.path.parent_path() / stem /
                 ((o.denoised && !args.denoise_only ? "%04d.denoised" : "%04d") + o.path.extension().string());
  }
  if (several_frames) {
    for (const auto& o : outputs)
      if (o.image && !has_frame_pattern(o.path.string())) {
        print_error(
            fmt::format("kozu render: {} {}: {} frames would overwrite one file: put the frame number in the "
                        "name, e.g. out/%04d.png",
                        o.flag, o.path.string(), frames.y - frames.x + 1));
        return false;
      }
    if (!args.checkpoint.empty() || !args.resume.empty()) {
      print_error("kozu render: --checkpoint and --resume take one frame at a time: render each frame with --frames N");
      return false;
    }
  }
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
      return false;
    }
  }
  return true;
}

// What every rank must agree on before rendering: what decides which pixels and samples a rank takes, and the
// film's layout.
uint64_t RenderJob::State::fingerprint() const {
  uint64_t f = base_scene_hash;
  const auto mix = [&f](const auto& v) { f = hash_words(&v, sizeof v, f); };
  for (const auto v :
       {res.x, res.y, window.origin.x, window.origin.y, window.size.x, window.size.y, opt.spp, opt.sample_begin,
        opt.max_depth, frames.x, frames.y, static_cast<int>(opt.direct), static_cast<int>(opt.filter),
        static_cast<int>(flags.aovs.size()), int{args.alpha}, int{denoising()}, int{!args.resume.empty()}})
    mix(v);
  mix(opt.seed);
  return f;
}

namespace {

// This process's temporary files in the texture conversion folder `dir` (and its procedural/ folder) that no
// registry knows: OpenImageIO's make_texture writes beside kozu's registered temporary name (".NAME.PID-N.tmp.tx" +
// ".RANDOM.temp.tx"). Every kozu temporary name starts with '.', holds ".tmp" and the process id.
void remove_own_conversion_temps(const std::filesystem::path& dir) {
  const std::string pid = std::to_string(static_cast<long>(getpid()));
  for (const std::filesystem::path& d : {dir, dir / "procedural"}) {
    std::error_code ec;
    for (auto it = std::filesystem::directory_iterator(d, ec); !ec && it != std::filesystem::directory_iterator();
         it.increment(ec)) {
      const std::string name = it->path().filename().string();
      if (name.size() > 1 && name[0] == '.' && name.find(".tmp") != std::string::npos &&
          (name.find("." + pid + "-") != std::string::npos || name.find("." + pid + ".") != std::string::npos)) {
        std::error_code rm;
        std::filesystem::remove(it->path(), rm);
      }
    }
  }
}

}  // namespace

// While it lives, ends the process with a message shortly before `budget` seconds since the process started
// (budget 0: never): the budget ran out before sampling could begin, and nothing was written. `convert_dir`: the
// texture conversion folder, cleaned of this process's temporary files first. It lives from before loading until the
// first frame's plan is made (render_frame): on a loaded machine the plan's calibrations (a write of each output's
// format, the denoiser on a small film) once took a 2 s budget to 2.08 s after loading had ended in time.
class BudgetWatch {
 public:
  BudgetWatch(double budget, const std::string& scene, std::filesystem::path convert_dir) {
    if (budget <= 0.0) return;
    thread_ = std::thread([this, budget, scene, convert_dir] {
      // Early enough that the message and the exit land inside the budget: tearing a large process down took
      // 78 ms on a loaded machine (AddressSanitizer's build), past an earlier 0.05 s margin.
      const double at = budget - 0.15;
      std::unique_lock lock(mutex_);
      while (!done_) {
        const double left = at - seconds_since_process_start();
        if (left <= 0.0) {
          std::fprintf(stderr,
                       "error: %s: --budget %g: the budget ran out while %s (%.2f s); nothing rendered: raise the "
                       "budget\n",
                       scene.c_str(), budget, stage_.load(), seconds_since_process_start());
          std::fflush(stderr);
          remove_temp_files_before_exit();
          remove_own_conversion_temps(convert_dir);
          std::_Exit(1);
        }
        cv_.wait_for(lock, std::chrono::duration<double>(std::min(left, 0.05)));
      }
    });
  }
  ~BudgetWatch() {
    if (!thread_.joinable()) return;
    {
      std::lock_guard lock(mutex_);
      done_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  BudgetWatch(const BudgetWatch&) = delete;
  BudgetWatch& operator=(const BudgetWatch&) = delete;
  // What the process is doing, for the message (a string literal).
  void set_stage(const char* stage) { stage_ = stage; }

 private:
  std::atomic<const char*> stage_{"the scene was loading"};
  std::mutex mutex_;
  std::condition_variable cv_;
  bool done_ = false;
  std::thread thread_;
};

int RenderJob::State::run() {
  t0 = Clock::now();
  scene_name = args.demo ? "<demo>" : args.scene;
  if (args.demo == !args.scene.empty()) {
    print_error("kozu render: give a scene file or --demo (not both)");
    return 1;
  }
  // A stop signal before sampling ends the command at once (the command's handlers: loading a large scene or
  // converting a texture is not waited for; the output probes and conversions are registered temporary files).
  RankGate ready(*this, "before rendering");
  if (!args.empty_flags.empty()) {
    print_error(fmt::format("kozu render: {}: expected a file name, got an empty one", args.empty_flags.front()));
    return 1;
  }
  // The command line and every output are checked before anything is loaded.
  if (!plan_outputs() || !check_scene_kind()) return 1;
  std::vector<std::filesystem::path> inputs;
  if (!args.demo) inputs.emplace_back(args.scene);
  try {
    flags = validate_flags(args);
    if (preloaded && !flags.overrides.empty())
      throw InputError("kozu render", "-D", "the scene is loaded already; overrides act on loading");
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
  // Under --budget a scene whose loading (or the first frame's plan) outlasts the budget (a huge mesh, a machine
  // under load) ends the process just before the budget does, instead of overrunning it; not under MPI (the ranks
  // must agree) nor in memory.
  const auto watch =
      std::make_shared<BudgetWatch>(flags.budget && !distributed() && !args.in_memory ? *flags.budget : 0.0, scene_name,
                                    TextureCache::convert_folder(texture_options()));
  start_watch = watch;
  if (!load()) return 1;
  watch->set_stage("the render was being prepared");
  load_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  if (const int sig = stop_signal()) {
    print_error(fmt::format("{}: interrupted by {} before rendering; nothing written", scene_name, signal_name(sig)));
    return 128 + sig;
  }
  if (!apply_settings() || !check_memory() || !plan_frames()) return 1;
  still = camera_key(scene->camera);
  // The scene's identity for checkpoints: its file's bytes and its inputs' names and sizes, read once for all frames.
  base_scene_hash = scene_hash(args, *scene);
  // Every rank loaded the scene and agrees on what to render.
  if (!ready.pass(0, fingerprint())) return 1;
  return run_frames();
}

int RenderJob::State::run_frames() {
  // From here the first stop signal ends sampling, and the images of the samples taken are still written.
  const std::shared_ptr<void> cooperative = hooks.cooperative ? hooks.cooperative(progress.cancel) : nullptr;
  int status = 0, frame = frames.x;
  frame_count = frames.y - frames.x + 1;
  for (; frame <= frames.y && status == 0; ++frame) {
    status = render_frame(frame, frames.y - frame + 1);
    ++frames_finished;
    if (status != kBudgetSpent) {
      RenderFrameReport r;
      r.frame = frame;
      r.status = status;
      r.written = last_written;
      r.film = last_summary;
      reports.push_back(std::move(r));
    }
  }
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
  if (!frame_stats.empty() && rank() == 0) {
    try {
      Json j;
      j["frames"] = frame_stats;
      j["process_seconds"] = seconds_since_process_start();
      if (flags.budget) j["budget"] = *flags.budget;
      write_file_atomic(args.stats, j.dump(2, ' ', false, Json::error_handler_t::replace) + "\n");
    } catch (const std::exception& e) {
      print_error(e.what());
      status = status ? status : 1;
    }
  }
  frames_done = true;
  return status;
}

RenderJob::RenderJob(RenderJobSettings settings, RenderJobHooks hooks) : s_(std::make_unique<State>()) {
  s_->args = std::move(settings);
  s_->hooks = std::move(hooks);
}

RenderJob::RenderJob(std::unique_ptr<Scene> scene, RenderJobSettings settings, RenderJobHooks hooks)
    : RenderJob(std::move(settings), std::move(hooks)) {
  s_->scene = std::move(scene);
  s_->preloaded = s_->scene != nullptr;
}

RenderJob::~RenderJob() = default;

int RenderJob::run() { return s_->run(); }
const std::vector<RenderFrameReport>& RenderJob::frames() const { return s_->reports; }
const Film& RenderJob::film() const { return s_->last_film; }
const Scene* RenderJob::scene() const { return s_->scene.get(); }
const RenderImages& RenderJob::images() const { return s_->images; }
void RenderJob::cancel() { s_->progress.cancel = true; }

double RenderJob::fraction_done() const {
  const State& s = *s_;
  const int frames = s.frame_count.load();
  if (frames <= 0) return 0.0;
  double in_frame = 0.0;
  if (const uint64_t total = s.frame_samples.load(); total > 0)
    in_frame = static_cast<double>(s.progress.samples_done.load() - s.frame_samples_base.load()) / total;
  const double limit = s.frame_time_limit.load();
  if (const int64_t start = s.frame_start_ns.load(); limit > 0.0 && start != 0) {
    const double elapsed = static_cast<double>(steady_now_ns() - start) * 1e-9;
    in_frame = std::max(in_frame, elapsed / limit);
  }
  return std::clamp((s.frames_finished.load() + std::min(in_frame, 1.0)) / frames, 0.0, 1.0);
}
bool RenderJob::exit_without_teardown() const {
  return s_->frames_done && s_->flags.budget.has_value() && !s_->distributed();
}

namespace {

// The camp rules the demo is made for (the Raytracing camp): camp 6 gave a still 123 s, camp 10 an animation 256 s,
// each from the process's start.
constexpr const char* kDemoBudget = "123";
constexpr const char* kDemoAnimationBudget = "256";
// --demo-animation: an arc of the camera past the still life, 1 s at 24 fps. On 2 cores 256 s hold 24 frames of
// 640 x 360 at about 6 spp each, denoised; 48 frames of 960 x 540 got 1.5 spp, too few for any filter.
constexpr const char* kDemoAnimation =
    R"({"fps": 24, "frames": 24, "camera": [)"
    R"({"time": 0, "position": [-0.75, 1.16, 2.3], "look_at": [-0.1, 0.9, -0.4]},)"
    R"({"time": 0.5, "position": [-0.35, 1.22, 2.45], "look_at": [-0.05, 0.9, -0.4]},)"
    R"({"time": 1, "position": [0.15, 1.3, 2.5], "look_at": [0.0, 0.88, -0.4]}]})";
constexpr const char* kDemoAnimationResolution = "640x360";

}  // namespace

// What --demo and --demo-animation mean when the command line leaves them open: the camp's budget with the
// denoiser; the animation's camera move at its default size.
void apply_demo_defaults(RenderJobSettings& args, bool animation) {
  if (animation) {
    args.demo = true;
    args.defines.insert(args.defines.begin(), std::string("/animation=") + kDemoAnimation);
    if (!args.resolution) args.resolution = kDemoAnimationResolution;
  }
  if (!args.demo || args.spp || args.time_limit || args.budget || args.resume.size() || args.sample_range) return;
  args.budget = animation ? kDemoAnimationBudget : kDemoBudget;
  if (!args.denoise_only) args.denoise = true;
  // The still takes the ensemble: on the demo it leaves 20 % less error than NL-means alone, with a third of its
  // stains (docs/production.md, the filters against each other), for about 3 s more at 1080p on 2 cores. The
  // animation's frames keep NL-means, whose shorter filter leaves their few seconds each to sampling.
  if (!animation && !args.denoiser) args.denoiser = "ensemble";
}

}  // namespace kozu
