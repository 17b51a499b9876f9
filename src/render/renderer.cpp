#include "render/renderer.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <memory>

namespace kozu {

namespace {

struct ThreadState {
  Arena arena;
  Sampler sampler;
  RayCounters rays;
  uint64_t paths = 0;
  explicit ThreadState(uint32_t seed) : sampler(seed) {}
};

struct Tile {
  int x0, y0, x1, y1;
};

using Clock = std::chrono::steady_clock;

}  // namespace

RenderResult render(const Scene& scene, const Integrator& integrator, Film& film, const RenderOptions& options,
                    RenderProgress* progress) {
  const Camera& camera = scene.camera;
  const Vec2i res = camera.resolution();
  const PixelFilter filter(options.filter);
  const uint32_t seed32 = static_cast<uint32_t>(options.seed ^ (options.seed >> 32));

  std::vector<Tile> tiles;
  const int ts = std::max(1, options.tile_size);
  for (int y = 0; y < res.y; y += ts)
    for (int x = 0; x < res.x; x += ts) tiles.push_back({x, y, std::min(x + ts, res.x), std::min(y + ts, res.y)});

  const int threads = options.threads > 0 ? options.threads : static_cast<int>(tbb::info::default_concurrency());
  tbb::task_arena arena(threads);
  tbb::enumerable_thread_specific<ThreadState> states([&] { return ThreadState(seed32); });

  const auto start = Clock::now();
  const bool timed = options.time_limit > 0.0;
  const auto deadline =
      start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.time_limit));
  std::atomic<bool> stop{false};
  const int target = options.spp > 0 ? options.spp : std::numeric_limits<int>::max();

  auto render_tile = [&](const Tile& t, int s0, int s1) {
    ThreadState& st = states.local();
    for (int s = s0; s < s1; ++s) {
      // Check between samples: a pass never overruns the deadline by more than one sample per tile.
      if (stop.load(std::memory_order_relaxed)) return;
      if ((timed && Clock::now() >= deadline) || (progress && progress->cancel.load(std::memory_order_relaxed))) {
        stop.store(true, std::memory_order_relaxed);
        return;
      }
      for (int y = t.y0; y < t.y1; ++y) {
        for (int x = t.x0; x < t.x1; ++x) {
          st.sampler.start(static_cast<uint32_t>(x), static_cast<uint32_t>(y), static_cast<uint32_t>(s));
          const Vec4 u = st.sampler.next_4d();  // pixel filter (x, y), lens (z, w)
          const Vec2 offset = filter.sample(Vec2(u.x, u.y));
          const Ray ray = camera.generate_ray(Vec2(x + 0.5f, y + 0.5f) + offset, Vec2(u.z, u.w));
          const Rgb L = integrator.li(ray, st.sampler, st.arena, st.rays);
          st.arena.reset();
          ++st.paths;
          // Non-finite or negative samples are discarded and counted, never written.
          if (is_finite(L) && L.r >= 0.0f && L.g >= 0.0f && L.b >= 0.0f)
            film.add_sample(x, y, L);
          else
            film.add_discarded(x, y);
        }
      }
      if (progress)
        progress->samples_done.fetch_add(static_cast<uint64_t>(t.x1 - t.x0) * (t.y1 - t.y0), std::memory_order_relaxed);
    }
  };

  int done = 0;
  RenderResult result;
  arena.execute([&] {
    while (done < target && !stop.load()) {
      // A pass adds half as many samples as were taken so far, between 1 and 16 (1, 1, 1, 1, 2, 3,
      // 4, 6, 9, 14, 16, ...): a stop at any time leaves pixel counts within one pass of each
      // other, and per-pass overhead stays small even for tiny images.
      const int pass = std::min({target - done, std::clamp(done / 2, 1, 16)});
      tbb::parallel_for(tbb::blocked_range<size_t>(0, tiles.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) render_tile(tiles[i], done, done + pass);
      });
      done += pass;
    }
  });

  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  result.hit_time_limit = timed && stop.load() && !(progress && progress->cancel.load());
  result.threads = threads;
  for (const ThreadState& st : states) {
    result.rays += st.rays;
    result.paths += st.paths;
  }
  result.film = film.summary();
  return result;
}

}  // namespace kozu
