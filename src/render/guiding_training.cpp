#include "render/guiding_training.h"

#include "scene/filter.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <limits>
#include <optional>

namespace kozu {

namespace {

using Clock = std::chrono::steady_clock;

// The training's own seed: its samples are not the image's.
constexpr uint32_t kTrainingSeed = 0x6A09E667u;
constexpr int kMaxPasses = 20;

}  // namespace

GuidingTraining train_guiding(const Scene& scene, PathIntegrator& integrator, GuidingField& field, const Film& film,
                              const RenderSettings& options, RenderProgress* progress) {
  const auto start = Clock::now();
  GuidingTraining out;
  // Every other pixel in x and y of this process's tiles, in image coordinates.
  std::vector<Vec2i> pixels;
  uint64_t rank_pixels = 0;
  for (int y = film.origin().y; y < film.origin().y + film.height(); ++y)
    for (int x = film.origin().x; x < film.origin().x + film.width(); ++x) {
      if (!renders_pixel(film, options, Vec2i(x, y))) continue;
      ++rank_pixels;
      if (x % 2 == 0 && y % 2 == 0) pixels.emplace_back(x, y);
    }
  if (pixels.empty()) pixels.emplace_back(film.origin());

  // The training's share of the samples and of the time.
  const double sample_budget = options.spp > 0 ? kTrainingShare * double(options.spp) * double(rank_pixels)
                                               : std::numeric_limits<double>::infinity();
  std::optional<Clock::time_point> deadline;
  auto cap = [&](Clock::time_point end) {
    const auto share = std::chrono::duration_cast<Clock::duration>((end - start) * kTrainingShare);
    deadline = deadline ? std::min(*deadline, start + share) : start + share;
  };
  if (options.time_limit > 0.0)
    cap(start + std::chrono::duration_cast<Clock::duration>(
                    std::chrono::duration<double>(std::min(options.time_limit, RenderSettings::kMaxTimeLimit))));
  if (progress && progress->deadline) cap(std::max(*progress->deadline, start));

  const PixelFilter filter(options.filter);
  const uint32_t seed = sampler_seed(options) ^ kTrainingSeed;
  const int threads = render_threads(options);
  tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
  tbb::task_arena arena(threads);
  tbb::enumerable_thread_specific<RenderThreadState> states([&] { return RenderThreadState(seed); });
  StopFlag stop{false};
  integrator.set_guiding(&field, true);

  double spent = 0.0, last_pass_seconds = 0.0;
  for (int k = 0; k < kMaxPasses; ++k) {
    const int samples = 1 << k;
    const double cost = double(samples) * double(pixels.size());
    if (spent + cost > sample_budget) break;
    const auto pass_start = Clock::now();
    if (deadline && pass_start + std::chrono::duration_cast<Clock::duration>(
                                     std::chrono::duration<double>(2.0 * last_pass_seconds)) > *deadline)
      break;
    if (progress && progress->cancel.load()) break;
    // Pass k takes samples 2^k - 1 .. 2^(k+1) - 2 of its pixels, so passes never repeat a sample.
    const int s0 = samples - 1;
    std::atomic<uint64_t> pass_paths{0};
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, pixels.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
        RenderThreadState& st = states.local();
        uint64_t done = 0;
        for (size_t i = r.begin(); i != r.end() && !stop.load(std::memory_order_relaxed); ++i) {
          if ((deadline && Clock::now() >= *deadline) || (progress && progress->cancel.load())) {
            stop.store(true);
            break;
          }
          for (int s = s0; s < s0 + samples; ++s) {
            const Ray ray = camera_sample(scene, filter, st.sampler, pixels[i].x, pixels[i].y, s);
            integrator.li(ray, st.sampler, st.arena, st.rays, stop);
            st.arena.reset();
            ++done;
          }
        }
        pass_paths.fetch_add(done, std::memory_order_relaxed);
      });
    });
    spent += cost;
    out.paths += pass_paths.load();
    last_pass_seconds = std::chrono::duration<double>(Clock::now() - pass_start).count();
    if (pass_paths.load() > 0) {
      field.refine(pass_paths.load());
      ++out.passes;
    }
    if (stop.load()) break;
  }
  integrator.set_guiding(&field, false);
  out.samples = (1 << out.passes) - 1;
  out.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  out.leaves = field.leaves();
  out.directional_nodes = field.directional_nodes();
  out.bytes = field.bytes();
  return out;
}

namespace {
void add_pass(RenderResult& total, const RenderResult& r) {
  total.rays += r.rays;
  total.paths += r.paths;
  total.threads = std::max(total.threads, r.threads);
  total.hit_time_limit = total.hit_time_limit || r.hit_time_limit;
  total.cancelled = total.cancelled || r.cancelled;
}
}  // namespace

RenderResult render_guided(const Scene& scene, PathIntegrator& integrator, GuidingField& field, Film& film,
                           const RenderSettings& options, RenderProgress* progress, const PassHook& hook,
                           GuidingTraining* training) {
  const auto start = Clock::now();
  auto seconds_since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  // What is left of the time limit (measured from here, as render() measures its own), 0 for none.
  auto time_left = [&](const RenderSettings& o) {
    return o.time_limit > 0.0 ? std::max(1e-3, o.time_limit - seconds_since(start)) : 0.0;
  };
  GuidingTraining t;
  if (options.sample_begin > 0 || film.summary().total_samples > 0) {
    t = train_guiding(scene, integrator, field, film, options, progress);
    RenderSettings o = options;
    o.time_limit = time_left(options);
    RenderResult r = render(scene, integrator, film, o, progress, hook);
    r.seconds = seconds_since(start);
    if (training) *training = t;
    return r;
  }
  t.in_image = true;
  RenderResult total;
  // The visible emission's supersampling is decided for the whole render's samples, not the first pass's
  // (render() would, with spp 1).
  const std::optional<Clock::time_point> deadline = render_deadline(options, progress, start);
  if (emission_supersampling_applies(film, options, {}, deadline.has_value())) {
    const std::atomic<bool> never{false};
    tbb::task_arena arena(render_threads(options));
    arena.execute([&] {
      film.set_emission_apart(supersample_emission(scene, integrator, film, options,
                                                   progress ? progress->cancel : never, {}, &total.emission,
                                                   deadline));
    });
    total.rays += total.emission.rays;
  }
  const int64_t target = options.spp > 0 ? options.spp : std::numeric_limits<int>::max();
  int64_t done = 0;
  double last_pass_seconds = 0.0;
  integrator.set_guiding(&field, true);
  for (int k = 0; k < kMaxPasses; ++k) {
    const int64_t pass = int64_t{1} << k;
    if (target - done - pass < 2 * pass) break;  // the rest must be at least the next pass's size
    // Under a time limit or a deadline: three times the predicted pass (twice the last) must be left.
    const double predicted = 2.0 * last_pass_seconds;
    if (options.time_limit > 0.0 && options.time_limit - seconds_since(start) < 3.0 * predicted) break;
    if (progress && progress->deadline &&
        std::chrono::duration<double>(*progress->deadline - Clock::now()).count() < 3.0 * predicted)
      break;
    if (progress && progress->cancel.load()) break;
    RenderSettings o = options;
    o.spp = static_cast<int>(done + pass);
    o.time_limit = time_left(options);
    const auto pass_start = Clock::now();
    const RenderResult r = render(scene, integrator, film, o, progress, hook);
    last_pass_seconds = seconds_since(pass_start);
    add_pass(total, r);
    t.paths += r.paths;
    if (r.paths > 0) {
      field.refine(r.paths);
      ++t.passes;
    }
    done += pass;
    t.samples = static_cast<int>(done);
    if (r.hit_time_limit || r.cancelled) break;
  }
  integrator.set_guiding(&field, false);
  t.seconds = seconds_since(start);
  t.leaves = field.leaves();
  t.directional_nodes = field.directional_nodes();
  t.bytes = field.bytes();
  if (!total.hit_time_limit && !total.cancelled && done < target) {
    RenderSettings o = options;
    o.time_limit = time_left(options);
    add_pass(total, render(scene, integrator, film, o, progress, hook));
  }
  total.seconds = seconds_since(start);
  total.film = film.summary();
  if (training) *training = t;
  return total;
}

}  // namespace kozu
