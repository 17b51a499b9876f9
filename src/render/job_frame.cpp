// One frame of a RenderJob (render/job.h): its camera, seed and outputs, rendered and written.
#include "core/file_io.h"
#include "core/process_clock.h"
#include "core/version.h"
#include "io/checkpoint_file.h"
#include "render/job_outputs.h"
#include "render/job_report.h"
#include "render/job_state.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace kozu {

using namespace render_job;

// The frame's camera and shapes at its time, and its seed.
bool RenderJob::State::pose_frame(Frame& f) {
  const int frame = f.number;
  // A different seed per frame: noise that stays put from frame to frame reads as a dirty lens.
  f.opt.seed = opt.seed + static_cast<uint64_t>(frame) * 0x9e3779b97f4a7c15ull;
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
    print_error(fmt::format("{}: /animation/camera: at frame {} (t = {:.4g} s): {}", scene_name, frame, at, e.what()));
    return false;
  }
  if (scene->has_media()) scene->set_media_view();
  // Moving shapes: their poses, then the hierarchy rebuilt (a camera-only animation keeps the first build).
  try {
    scene->pose_shapes(time);
  } catch (const std::invalid_argument& e) {
    print_error(fmt::format("{}: /animation/shapes: at frame {}: {}", scene_name, frame, e.what()));
    return false;
  }
  progress.samples_done = 0;
  return true;
}

// The frame's identity (what a checkpoint must match to be continued) and its film: new, or resumed.
bool RenderJob::State::open_film(Frame& f) {
  RenderIdentity& identity = f.identity;
  identity.kozu_version = KOZU_VERSION;
  identity.scene_hash = base_scene_hash ^ (animated ? hash_words(&f.number, sizeof f.number) : 0);
  identity.seed = f.opt.seed;
  identity.max_depth = max_depth;
  identity.direct = direct_lighting_name(f.opt.direct);
  identity.filter = PixelFilter::name(f.opt.filter);
  identity.resolution = res;
  identity.window_origin = window.origin;
  identity.window_size = window.size;
  identity.sample_begin = f.opt.sample_begin;
  // Parts of a split render carry their per-pixel sample counts, for kozu merge.
  f.aovs = flags.aovs;
  if ((flags.sample_range || args.crop) && std::find(f.aovs.begin(), f.aovs.end(), Aov::SampleCount) == f.aovs.end())
    f.aovs.push_back(Aov::SampleCount);
  identity.features = needs_features(f.aovs) || denoising();
  identity.positions = needs_positions(f.aovs);
  identity.alpha = args.alpha;
  Film& film = f.film;
  try {
    film = args.resume.empty() ? Film(window.size.x, window.size.y, window.origin)
                               : load_checkpoint(args.resume, identity);
    if (identity.features && !film.has_features()) film.enable_features();
    if (identity.positions && !film.has_positions()) film.enable_positions();
    if (identity.alpha && !film.has_alpha()) film.enable_alpha();
    if (distributed() && !args.resume.empty()) {
      // Each rank keeps the resumed samples of its own tiles only: the final sum must hold each pixel once.
      for (int y = 0; y < window.size.y; ++y)
        for (int x = 0; x < window.size.x; ++x) {
          const Vec2i p = window.origin + Vec2i(x, y);
          if (renders_pixel(film, f.opt, p)) continue;
          film.clear_pixel(static_cast<size_t>(y) * window.size.x + x);
        }
    }
  } catch (const InputError& e) {
    print_error(e.what());
    return false;
  }
  f.resumed = film.summary();
  return true;
}

// --budget: sampling ends when what is left of the budget, measured from the process's start, is what the writes
// need (estimated from the image size, with margin); frames still to render share it equally. A frame is begun only
// when its setting up and writing still fit, so the frames stop when the budget does. 0, 1 or kBudgetSpent.
int RenderJob::State::plan_budget(Frame& f, int frames_left) {
  if (!finish_cost) {
    // The EXRs' channels besides RGB: alpha and the AOVs, which the write calibration writes too.
    int extra = args.alpha ? 1 : 0;
    for (Aov a : f.aovs) extra += static_cast<int>(aov_channel_count(a));
    finish_cost = finish_seconds(window.size, f.outputs, flags.tonemap, !args.checkpoint.empty(), denoising(),
                                 args.denoise_only, flags.denoiser, extra);
    // The denoiser is planned for only when every frame's share of it leaves a quarter of the budget to sampling;
    // otherwise the raw images are the product, denoised only where sampling ended early (a sample cap).
    const double budget_left = *flags.budget - seconds_since_process_start();
    denoise_planned = denoising() && frames_left * finish_cost->total(true) <= 0.75 * budget_left;
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
  const double now = seconds_since_process_start();
  // What a frame costs besides sampling: the calibrated writes until a frame was measured, then what the last
  // one took (setting it up, the hierarchy, the writes) with margin; the statistics and the exit once. A frame is
  // begun when that fits. The last frame then keeps at least the calibrated cost where it fits: its denoiser runs
  // only before denoise_deadline, which the calibration sets, and a frame before it that overran is absorbed by
  // the frames after it, the last one by nothing (where it does not fit, the last frame is still rendered, raw).
  const double calibrated = finish_cost->total(denoise_planned) - finish_cost->fixed;
  double per_frame = f.number > frames.x ? std::max(1.25 * frame_overhead, finish_cost->raw / 1.5) : calibrated;
  reserve = per_frame + finish_cost->fixed;
  if (f.number > frames.x && now + reserve > *flags.budget) return kBudgetSpent;
  // The last frame's denoiser starts only if, after sampling, its raw writes and what else came before the
  // denoiser on the frames before it (denoise_lag, twice over) still leave the filter's expected cost: the
  // calibrated margins alone (1.5 times a write of a few milliseconds) left a 160x90 frame 1-3 ms late for it.
  // Nothing after the last frame absorbs its overrun, so it keeps one more filter's cost besides: on a loaded
  // 2-core CI machine its sampling and writes once outran the margins above and its filter was skipped.
  const double last = std::max(calibrated, 2.0 * denoise_lag + (calibrated - finish_cost->raw)) +
                      (denoise_planned ? finish_cost->filter : 0.0);
  if (f.number > frames.x && frames_left == 1 && now + last + finish_cost->fixed <= *flags.budget) {
    per_frame = std::max(per_frame, last);
    reserve = per_frame + finish_cost->fixed;
  }
  const double sampling =
      std::max((*flags.budget - now - finish_cost->fixed - per_frame * frames_left) / frames_left, 1e-6);
  f.sampling_deadline = now + sampling;
  f.filter_deadline = *flags.budget - finish_cost->fixed - finish_cost->denoised_writes;
  // The plan above keeps the margins; whether to start the filter is decided on its expected cost, since the filter
  // itself stops at filter_deadline (the margin once made a last frame skip its filter by a few milliseconds).
  f.denoise_deadline = f.filter_deadline - finish_cost->filter;
  progress.deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(sampling));
  // The time limit only sizes the progress bar's ETA; the deadline above ends sampling.
  f.opt.time_limit = f.opt.time_limit > 0.0 ? std::min(f.opt.time_limit, sampling) : sampling;
  return 0;
}

// Partial images and checkpoints between passes.
PassHook RenderJob::State::pass_hook(Frame& f) {
  PassHook hook;
  f.render_start = Clock::now();
  f.next_partial = flags.partial_every.value_or(0.0);
  f.next_checkpoint = flags.checkpoint_every.value_or(0.0);
  if (!flags.partial_every && !flags.checkpoint_every) return hook;
  hook.interval = std::min(flags.partial_every.value_or(1e30), flags.checkpoint_every.value_or(1e30));
  hook.every = [this, &f] {
    const auto since_start = [&f] { return std::chrono::duration<double>(Clock::now() - f.render_start).count(); };
    const double t = since_start();
    f.render_seconds = t;
    if (flags.partial_every && t >= f.next_partial) {
      std::vector<std::string> written;
      write_images(f, true, written, f.partial_failures);
      ++f.partial_images;
      f.next_partial = since_start() + *flags.partial_every;
    }
    if (flags.checkpoint_every && t >= f.next_checkpoint) {
      try {
        save_checkpoint(args.checkpoint, f.identity, f.film);
        ++f.checkpoints;
      } catch (const std::exception& e) {
        f.partial_failures.push_back(e.what());
      }
      f.next_checkpoint = since_start() + *flags.checkpoint_every;
    }
  };
  return hook;
}

// What an image carries besides its pixels: the render's attributes, the camera, alpha and the AOVs.
ImageExtras RenderJob::State::image_extras(const Frame& f, bool partial) const {
  ImageExtras extras;
  if (flags.budget) extras.exr_compression = kBudgetExrCompression;
  extras.origin = window.origin;
  extras.full_size = res;
  const Film::Summary sum = f.film.summary();
  extras.attributes = {{"kozu:version", KOZU_VERSION},
                       {"kozu:scene_hash", fmt::format("{:016x}", f.identity.scene_hash)},
                       {"kozu:seed", std::to_string(f.opt.seed)},
                       {"kozu:sample_begin", std::to_string(f.opt.sample_begin)},
                       {"kozu:spp_mean", fmt::format("{}", sum.mean_spp)},
                       {"kozu:spp_min", std::to_string(sum.min_spp)},
                       {"kozu:spp_max", std::to_string(sum.max_spp)},
                       {"kozu:render_seconds", fmt::format("{:.3f}", f.render_seconds)},
                       {"kozu:partial", partial ? "1" : "0"},
                       {"kozu:negative_pixels", f.opt.keep_negative ? "keep" : "clamp"}};
  // OpenEXR's standard camera attributes, of the frame's camera (scene/camera.h gives the conventions).
  extras.matrices = {{"worldToCamera", scene->camera.exr_world_to_camera()}};
  if (const auto ndc = scene->camera.exr_world_to_ndc()) extras.matrices.emplace_back("worldToNDC", *ndc);
  if (args.alpha) {
    // OpenEXR's alpha channel: coverage, the fraction of the pixel's samples whose camera ray met geometry.
    extras.channels = {"A"};
    extras.data = f.film.alpha();
  }
  add_aov_channels(f.film, f.aovs, extras);
  return extras;
}

// The visible emission re-estimated where its samples disagree (render/emission_refine.h), then the rest filtered;
// the time it took in f.denoise_seconds.
std::vector<float> RenderJob::State::denoised_image(Frame& f) {
  const auto t = Clock::now();
  // Under --budget the re-estimation stops where the filter's expected cost is all that is left before the
  // filter's deadline: a machine that became slower after the budget's calibration would otherwise carry it past
  // the budget. The pixels it did not reach keep their visible emission in the filtered radiance.
  const double refine_deadline =
      finish_cost ? f.filter_deadline - (finish_cost->filter - finish_cost->refine) : f.filter_deadline;
  const auto refine_expired = [&] { return flags.budget && seconds_since_process_start() > refine_deadline; };
  const VisibleEmission emission =
      refine_emission(*scene, *f.integrator, f.film, f.opt, {}, &f.refined, refine_expired);
  // Past the filter's deadline (under --budget) either filter stops where it is and degrades (denoiser.h,
  // feature_regression.h).
  const double deadline = f.filter_deadline;
  const auto expired = [&] { return flags.budget && seconds_since_process_start() > deadline; };
  std::vector<float> clean = run_denoiser(flags.denoiser, f.film, &emission, expired, flags.threads);
  f.denoise_seconds = std::chrono::duration<double>(Clock::now() - t).count();
  return clean;
}

// The images' pixels below 0 as 0 ("negative_pixels": "clamp", render_settings.h), but for a --sample-range part,
// whose signed means the merge weighs into the whole render's.
void RenderJob::State::clamp_negative(const Frame& f, std::vector<float>& pixels) const {
  if (f.opt.keep_negative || flags.sample_range) return;
  for (float& v : pixels) v = std::max(v, 0.0f);
}

// A render in memory keeps what its outputs would hold.
void RenderJob::State::keep_images(Frame& f) {
  const ImageExtras extras = image_extras(f, false);
  images.width = window.size.x;
  images.height = window.size.y;
  images.rgb = f.film.rgb();
  clamp_negative(f, images.rgb);
  images.channels = extras.channels;
  images.data = extras.data;
  images.layers.clear();
  if (args.alpha) images.layers.emplace_back("alpha", 1);
  for (Aov a : f.aovs) images.layers.emplace_back(aov_name(a), static_cast<int>(aov_channel_count(a)));
  images.denoised.clear();
  if (denoising()) {
    images.denoised = denoised_image(f);
    clamp_negative(f, images.denoised);
  }
}

// Writes every image output from the film as it is (a partial image, or the final one).
void RenderJob::State::write_images(Frame& f, bool partial, std::vector<std::string>& written,
                                    std::vector<std::string>& failures) {
  if (args.in_memory) {
    if (!partial) keep_images(f);
    return;
  }
  std::vector<float> rgb = f.film.rgb();
  clamp_negative(f, rgb);
  const ImageExtras extras = image_extras(f, partial);
  const std::vector<OutputFile>& outs = f.outputs;
  std::vector<std::optional<std::string>> errors(outs.size());
  std::vector<char> wrote(outs.size(), 0);  // one byte each: written in parallel
  // The images are written in parallel (compression is most of a write).
  const auto write_all = [&](const std::vector<float>& pixels, auto&& takes) {
    tbb::parallel_for(size_t{0}, outs.size(), [&](size_t i) {
      const OutputFile& o = outs[i];
      if (!o.image || !takes(o)) return;
      try {
        write_image(o.path, window.size.x, window.size.y, pixels, flags.tonemap, extras);
        wrote[i] = 1;
        errors[i].reset();
      } catch (const std::exception& e) {
        errors[i] = e.what();
      }
    });
  };
  // Partial images are the raw render only (denoising takes seconds), under every name but the extra
  // NAME.denoised ones; under --budget --denoise-only writes the raw image under its names first, replaced by the
  // denoised one if it fits.
  const bool budgeted = flags.budget.has_value();
  if (partial || !denoising()) {
    write_all(rgb, [&](const OutputFile& o) { return !o.denoised || args.denoise_only; });
  } else {
    write_all(rgb, [&](const OutputFile& o) { return !o.denoised || (args.denoise_only && budgeted); });
    std::vector<float>().swap(rgb);  // written: its memory goes to the denoiser
    const double now = seconds_since_process_start();
    denoise_lag = std::max(denoise_lag, now - f.sampling_deadline);
    if (now <= f.denoise_deadline) {
      std::vector<float> clean = denoised_image(f);
      clamp_negative(f, clean);
      write_all(clean, [](const OutputFile& o) { return o.denoised; });
    } else {
      f.denoise_skipped = true;
    }
  }
  for (size_t i = 0; i < outs.size(); ++i) {
    if (wrote[i]) written.push_back(outs[i].path.string());
    if (errors[i]) failures.push_back(*errors[i]);
  }
}

// --stats: the frame's statistics, in a file of their own or gathered for the animation's one file.
void RenderJob::State::write_frame_stats(Frame& f, const RenderResult& result, int signal,
                                         Clock::time_point finish_start, const std::vector<std::string>& written,
                                         std::vector<std::string>& failures) {
  try {
    Json j = render_stats(*scene, scene_name, f.opt, max_depth, result, load_seconds, signal,
                          signal ? signal_name(signal) : std::string(), written);
    if (animated) j["frame"] = f.number;
    if (f.guiding)
      j["guiding"] = {{"passes", f.guiding->passes},
                      {"in_image", f.guiding->in_image},
                      {"samples", f.guiding->samples},
                      {"paths", f.guiding->paths},
                      {"seconds", f.guiding->seconds},
                      {"leaves", f.guiding->leaves},
                      {"directional_nodes", f.guiding->directional_nodes},
                      {"bytes", f.guiding->bytes}};
    if (flags.budget) {
      j["budget"] = *flags.budget;
      j["budget_reserve_seconds"] = reserve;
    }
    // "direct": "ltc": how much of the image its control variate took part in (docs/lights.md). A rank's own tiles
    // only under MPI, so not reported there.
    if (const ControlVariateStats& cv = result.control_variate; cv.pixels > 0 && !distributed())
      j["ltc"] = {{"pixels", cv.pixels},
                  {"pixels_taking", cv.pixels_taking},
                  {"samples_taking", cv.samples > 0.0 ? cv.samples_taking / cv.samples : 0.0}};
    j["partial_images"] = f.partial_images;
    if (denoising()) {
      j["denoise_seconds"] = f.denoise_seconds;
      j["denoise_emission_pixels"] = f.refined.pixels;
      j["denoise_emission_samples"] = f.refined.samples;
      j["denoise_emission_seconds"] = f.refined.seconds;
    }
    j["checkpoints"] = f.checkpoints;
    if (!args.resume.empty()) {
      j["resumed_from"] = args.resume;
      j["resumed_samples"] = f.resumed.total_samples;
    }
    j["sample_begin"] = f.opt.sample_begin;
    j["mpi_ranks"] = rank_count();
    j["window"] = {window.origin.x, window.origin.y, window.size.x, window.size.y};
    j["write_seconds"] = std::chrono::duration<double>(Clock::now() - finish_start).count();
    j["process_seconds"] = seconds_since_process_start();
    if (stats_per_frame || !several_frames)
      write_file_atomic(frame_path(args.stats, f.number), j.dump(2, ' ', false, Json::error_handler_t::replace) + "\n");
    else
      frame_stats.push_back(j);
  } catch (const std::exception& e) {
    failures.push_back(e.what());
  }
}

// The frame's warnings, its summary line and its failed writes, on stderr.
void RenderJob::State::report_frame(const Frame& f, const RenderResult& result, int signal,
                                    const std::vector<std::string>& written,
                                    const std::vector<std::string>& failures) const {
  if (failures.empty() && !f.partial_failures.empty()) {
    std::fprintf(stderr, "warning: %zu partial write%s failed, the first: %s\n", f.partial_failures.size(),
                 f.partial_failures.size() == 1 ? "" : "s", f.partial_failures.front().c_str());
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
    std::fprintf(
        stderr, "kozu: %s%s%s %dx%d, %.1f spp in %.2f s (%spaths/s, %srays/s, %d threads%s), wrote %s\n",
        signal ? fmt::format("interrupted by {}: ", signal_name(signal)).c_str() : "", scene_name.c_str(),
        animated ? fmt::format(" frame {}", f.number).c_str() : "", res.x, res.y, result.film.mean_spp, result.seconds,
        format_rate(paths_per_second).c_str(), format_rate(rays_per_second).c_str(), result.threads,
        result.film.discarded_samples ? fmt::format(", {} NaN samples discarded", result.film.discarded_samples).c_str()
                                      : "",
        join(written, "nothing").c_str());
  }
  if (f.denoise_skipped)
    std::fprintf(stderr,
                 "warning: %s%s: --denoise: skipped: the denoiser needs about %.1f s at %dx%d, which the --budget "
                 "did not leave; %s\n",
                 scene_name.c_str(), animated ? fmt::format(" frame {}", f.number).c_str() : "",
                 finish_cost ? finish_cost->denoised : 0.0, window.size.x, window.size.y,
                 args.denoise_only ? "the raw image was written under its names" : "the raw images were written");
  for (const auto& failure : failures) print_error(failure);
}

int RenderJob::State::render_frame(int frame, int frames_left) {
  const auto frame_start = Clock::now();
  RankGate frame_ready(*this, fmt::format("before frame {}", frame));
  last_written.clear();
  last_film = Film();  // the last frame's film is released before this one's is made
  last_summary = {};
  Frame f;
  f.number = frame;
  f.opt = opt;
  f.outputs = animated ? frame_outputs(frame) : outputs;
  if (animated && !pose_frame(f)) return 1;
  if (!open_film(f)) return 1;
  PathIntegrator integrator(*scene, max_depth, f.opt.direct);
  f.integrator = &integrator;
  if (flags.budget)
    if (const int status = plan_budget(f, frames_left); status != 0) return status;
  start_watch.reset();  // the plan is made: from here the budget's deadlines govern
  const PassHook hook = pass_hook(f);
  // A signal while the frame was set up: nothing of it was sampled (a resumed film still has its samples to write).
  // Under MPI that rank's stop is agreed on like a failure, so no rank waits for it in the reduction.
  const int early_signal = f.resumed.total_samples == 0 ? stop_signal() : 0;
  if (!frame_ready.pass(early_signal ? 128 + early_signal : 0, static_cast<uint64_t>(frame))) {
    if (!early_signal) return 1;
    print_error(fmt::format("{}: interrupted by {} before frame {} was rendered; nothing written for it", scene_name,
                            signal_name(early_signal), frame));
    return 128 + early_signal;
  }
  // From here a stop signal ends sampling, and the images are still written. The frame's share of the samples, for
  // the progress bar and RenderJob::fraction_done.
  frame_samples_base = progress.samples_done.load();
  frame_samples = static_cast<uint64_t>(std::max(f.opt.spp - f.opt.sample_begin, 0)) * window.size.x * window.size.y;
  frame_time_limit = f.opt.time_limit;
  frame_start_ns = steady_now_ns();
  std::optional<ProgressBar> bar;
  if (!args.quiet && rank() == 0 && isatty(STDERR_FILENO))
    bar.emplace(progress, frame_samples.load(), f.opt.time_limit);
  // Path guiding: its training passes are the frame's first samples (render/guiding_training.h).
  std::optional<GuidingField> field;
  if (f.opt.guiding) field.emplace(scene->center(), scene->radius());
  RenderResult result =
      field ? render_guided(*scene, integrator, *field, f.film, f.opt, &progress, hook, &f.guiding.emplace())
            : render(*scene, integrator, f.film, f.opt, &progress, hook);
  if (bar) bar->stop();
  f.render_seconds = result.seconds;
  // "ltc"'s pixel memory is kept for the checkpoint alone (render/checkpoint.h), and only a single process's: a
  // rank's holds its own tiles.
  if (args.checkpoint.empty() || distributed()) f.film.release_memory();
  const auto finish_start = Clock::now();
  if (distributed()) {
    if (!hooks.ranks->reduce(f.film, result.rays, result.paths)) return 1;
    result.seconds = hooks.ranks->max(result.seconds);
    if (rank() != 0) {
      const int sig = stop_signal();
      return sig ? 128 + sig : 0;  // rank 0 writes
    }
    result.film = f.film.summary();
    f.render_seconds = result.seconds;
  }

  // Every output is attempted; failures are reported with what was written. A partial write that failed is
  // reported once, unless the final write of that output then worked.
  std::vector<std::string> written, failures;
  write_images(f, false, written, failures);
  if (!args.checkpoint.empty()) {
    try {
      save_checkpoint(args.checkpoint, f.identity, f.film);
      ++f.checkpoints;
      written.push_back(args.checkpoint);
      f.film.release_memory();
    } catch (const std::exception& e) {
      failures.push_back(e.what());
    }
  }
  const int signal = stop_signal();
  if (!args.stats.empty()) write_frame_stats(f, result, signal, finish_start, written, failures);
  report_frame(f, result, signal, written, failures);
  frame_overhead = std::chrono::duration<double>(Clock::now() - frame_start).count() - std::max(result.seconds, 0.0);
  int status = signal ? 128 + signal : 0;  // as the signal's default action would report it (130, 143, 129)
  if (!failures.empty()) {
    print_error(fmt::format("{} output{} failed; written: {}", failures.size(), failures.size() == 1 ? "" : "s",
                            join(written, "none")));
    status = 1;
  }
  last_written = std::move(written);
  last_summary = result.film;
  last_film = std::move(f.film);
  return status;
}

}  // namespace kozu
