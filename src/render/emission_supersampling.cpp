#include "render/emission_supersampling.h"

#include "core/arena.h"
#include "core/huge_pages.h"
#include "core/rng.h"
#include "render/renderer.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

namespace kozu {

namespace {

using Clock = std::chrono::steady_clock;

// The streams of the pilot and of the estimate: apart from the render's and from each other's, and from those of a
// render of another sample range (kozu merge adds such renders, whose estimates must then be independent).
uint32_t stream_seed(const RenderSettings& options, uint32_t salt) {
  return hash_combine(sampler_seed(options) ^ salt, static_cast<uint32_t>(std::max(0, options.sample_begin)));
}

}  // namespace

bool emission_supersampling_applies(const Film& film, const RenderSettings& options,
                                    const EmissionSupersamplingSettings& settings, bool has_deadline) {
  // Each MPI rank decides over the whole window, as every other does (the choice is deterministic): no tile_ranks.
  const bool enough = options.spp > 0 ? options.spp - std::max(0, options.sample_begin) >= settings.min_spp
                                      : has_deadline;
  return options.emission_supersampling && !film.emission_decided() && !film.has_features() && enough &&
         film.summary().total_samples == 0;
}

std::vector<ApartEmission> supersample_emission(const Scene& scene, const Integrator& integrator, const Film& film,
                                                const RenderSettings& options, const std::atomic<bool>& stop,
                                                const EmissionSupersamplingSettings& settings,
                                                EmissionSupersamplingStats* stats,
                                                std::optional<Clock::time_point> deadline) {
  const auto start = Clock::now();
  std::vector<ApartEmission> out;
  const int w = film.width(), h = film.height();
  const size_t n = static_cast<size_t>(w) * h;
  // Under a deadline alone, planned after the pilot.
  int spp = options.spp > 0 ? options.spp - std::max(0, options.sample_begin) : 0;
  const bool plan_by_time = options.spp <= 0 && deadline.has_value();
  const PixelFilter filter(options.filter);
  const Vec2i origin = film.origin();
  RayCounters rays;
  uint64_t samples = 0;
  auto finish = [&] {
    if (stats) {
      stats->spp = spp;
      stats->pixels = out.size();
      stats->samples = samples;
      stats->seconds = std::chrono::duration<double>(Clock::now() - start).count();
      stats->rays = rays;
    }
    return out;
  };
  if (n == 0 || (spp <= 0 && !plan_by_time) || settings.pilot_samples <= 0) return finish();

  // 1. The pilot: per pixel, the lowest and highest luminance of the visible emission and of the rest of the light.
  struct Range {
    float lo = std::numeric_limits<float>::infinity(), hi = -std::numeric_limits<float>::infinity();
    void add(float v) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    void add(const Range& r) {
      lo = std::min(lo, r.lo);
      hi = std::max(hi, r.hi);
    }
    float spread() const { return hi - lo; }  // -inf or NaN when empty
  };
  PixelBuffer<Range> emitted(n), rest(n);  // 33 MB at full HD: huge pages (core/huge_pages.h)
  {
    // Under a deadline alone the pilot gives up once it has taken, or after a few rows looks set to take, more than
    // 1 / (min_spp + 1) of the time: the plan would then fall below min_spp anyway, and a short limit keeps the rest
    // of its time for the render's samples (a full-HD frame under a 20 s budget gives up after its first rows).
    const auto pilot_budget = plan_by_time ? (*deadline - start) / (settings.min_spp + 1) : Clock::duration{};
    constexpr int kRowsToProject = 8;
    std::atomic<bool> late{false};
    std::atomic<int> rows{0};  // rows the pilot sampled
    const auto too_late = [&] {
      if (late.load(std::memory_order_relaxed)) return true;
      const Clock::duration spent = Clock::now() - start;
      const int done = rows.load(std::memory_order_relaxed);
      if (spent > pilot_budget || (done >= kRowsToProject && spent / done * h > pilot_budget)) {
        late.store(true, std::memory_order_relaxed);
        return true;
      }
      return false;
    };
    tbb::enumerable_thread_specific<RenderThreadState> workers(
        [seed = stream_seed(options, 0x9170705u)] { return RenderThreadState(seed); });
    tbb::parallel_for(0, h, [&](int y) {
      if (plan_by_time && too_late()) return;
      RenderThreadState& wk = workers.local();
      for (int x = 0; x < w && !stop.load(std::memory_order_relaxed); ++x) {
        const size_t i = static_cast<size_t>(y) * w + x;
        for (int s = 0; s < settings.pilot_samples; ++s) {
          const Ray ray = camera_sample(scene, filter, wk.sampler, origin.x + x, origin.y + y, s);
          PixelFeatures f;
          // Ranges, not a low-variance estimate: without "ltc"'s control variate, which would pay for its probes and
          // closed form at every pixel (PixelMemory::learnt_skip; the render's own first samples pay them once).
          PixelMemory no_control_variate;
          no_control_variate.learnt_skip = 1;
          const Rgb L = integrator.li_pixel(ray, wk.sampler, wk.arena, wk.rays, stop, &f, &no_control_variate);
          wk.arena.reset();
          if (!sample_counts(L, integrator.signed_samples())) continue;
          const float e = luminance(f.emission);
          emitted[i].add(e);
          rest[i].add(luminance(L) - e);
        }
      }
      rows.fetch_add(1, std::memory_order_relaxed);
    });
    for (const RenderThreadState& wk : workers) rays += wk.rays;
    samples += static_cast<uint64_t>(rows.load()) * static_cast<uint64_t>(w) * settings.pilot_samples;
    if (stop.load() || late.load()) return finish();
  }
  if (plan_by_time) {
    // The samples a pixel the time left allows at the pilot's pace (its samples are the render's, with features).
    const auto now = Clock::now();
    const double per_sample = std::chrono::duration<double>(now - start).count() / settings.pilot_samples;
    const double left = std::chrono::duration<double>(*deadline - now).count();
    spp = per_sample > 0.0 && left > 0.0
              ? static_cast<int>(std::min(left / per_sample, double(std::numeric_limits<int>::max() / 2)))
              : 0;
    if (spp < settings.min_spp) return finish();
  }

  // 2. The choice: where the visible emission's spread over the pixel's neighbourhood is large, and more than
  // twice the rest's. (At an edge between an emitter of radiance E and a surface of radiance S, estimating the
  // emission apart removes a variance proportional to E² − 2 E S: a loss where the surface is about as bright,
  // as a white furnace's sphere against its sky.) The largest spreads first, within the budget.
  struct Candidate {
    uint32_t index;
    float jump;
  };
  std::vector<Candidate> candidates;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      Range e, r;
      for (int ny = std::max(0, y - 1); ny <= std::min(h - 1, y + 1); ++ny)
        for (int nx = std::max(0, x - 1); nx <= std::min(w - 1, x + 1); ++nx) {
          const size_t j = static_cast<size_t>(ny) * w + nx;
          e.add(emitted[j]);
          r.add(rest[j]);
        }
      const float jump = e.spread();
      if (jump > 0.0f && jump > settings.relative_jump * std::abs(e.hi) && jump > 2.0f * r.spread())
        candidates.push_back({static_cast<uint32_t>(static_cast<size_t>(y) * w + x), jump});
    }
  PixelBuffer<Range>().swap(emitted);
  PixelBuffer<Range>().swap(rest);
  const int64_t k = std::clamp<int64_t>(int64_t{settings.factor} * spp, settings.min_samples,
                                        std::max(settings.min_samples, settings.max_samples));
  const double budget = settings.budget * spp * static_cast<double>(n);
  const size_t chosen = std::min(candidates.size(), static_cast<size_t>(std::max(0.0, budget / double(k))));
  // The index breaks ties: the choice is deterministic.
  const auto larger = [](const Candidate& a, const Candidate& b) {
    return a.jump != b.jump ? a.jump > b.jump : a.index < b.index;
  };
  std::partial_sort(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(chosen), candidates.end(),
                    larger);
  candidates.resize(chosen);
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& a, const Candidate& b) { return a.index < b.index; });

  // 3. The estimates, each from its pixel's own stream (deterministic for a seed at any thread count).
  std::vector<std::optional<ApartEmission>> values(chosen);
  {
    tbb::enumerable_thread_specific<RenderThreadState> workers(
        [seed = stream_seed(options, 0x5e1ec7u)] { return RenderThreadState(seed); });
    tbb::parallel_for(size_t{0}, chosen, [&](size_t c) {
      RenderThreadState& wk = workers.local();
      const uint32_t i = candidates[c].index;
      const int x = origin.x + static_cast<int>(i % static_cast<uint32_t>(w)),
                y = origin.y + static_cast<int>(i / static_cast<uint32_t>(w));
      Vec3d sum(0.0), sq(0.0);
      int64_t valid = 0;
      for (int64_t s = 0; s < k; ++s) {
        if (stop.load(std::memory_order_relaxed)) return;  // unfinished: the pixel keeps its emission in its samples
        if (const auto e =
                visible_emission_sample(scene, integrator, filter, options, wk, x, y, static_cast<int>(s), stop)) {
          const Vec3d v(e->r, e->g, e->b);
          sum += v;
          sq += v * v;
          ++valid;
        }
      }
      if (valid == 0 || stop.load()) return;
      const double m = static_cast<double>(valid);
      const Vec3d mean = sum / m;
      // The variance of the mean as if the samples were independent: an overestimate for stratified ones.
      const Vec3d var = valid > 1 ? glm::max((sq - m * mean * mean) / (m - 1.0), Vec3d(0.0)) / m : Vec3d(0.0);
      values[c] = ApartEmission{i, Vec3(mean), Vec3(var)};
    });
    for (const RenderThreadState& wk : workers) rays += wk.rays;
  }
  for (size_t c = 0; c < chosen; ++c)
    if (values[c]) {
      out.push_back(*values[c]);
      samples += static_cast<uint64_t>(k);
    }
  return finish();
}

}  // namespace kozu
