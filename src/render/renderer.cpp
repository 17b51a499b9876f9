#include "render/renderer.h"

#include "render/adaptive_sampling.h"
#include "render/emission_supersampling.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <unordered_map>

namespace kozu {

namespace {

using ThreadState = RenderThreadState;

struct Tile {
  int x0, y0, x1, y1;
};

using Clock = std::chrono::steady_clock;

// The first sample is taken in four levels: pixels on the lattice of stride 8, then those of stride 4, 2 and 1
// not on a coarser one (in image coordinates, so any tile size works).
constexpr int kFirstPassLevels = 4;
int level_stride(int level) { return 8 >> level; }
bool in_level(int x, int y, int level) {
  const int s = level_stride(level);
  if (x % s != 0 || y % s != 0) return false;
  return level == 0 || x % (2 * s) != 0 || y % (2 * s) != 0;
}

// Raises `stop` at the deadline or when `cancel` is set, until finish() is called.
class Watchdog {
 public:
  Watchdog(std::atomic<bool>& stop, const std::atomic<bool>* cancel, std::optional<Clock::time_point> deadline)
      : stop_(stop), cancel_(cancel), deadline_(deadline) {
    thread_ = std::thread([this] { run(); });
  }
  ~Watchdog() { finish(); }
  void finish() {
    {
      std::lock_guard lock(mutex_);
      if (finished_) return;
      finished_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  bool deadline_reached() const { return deadline_reached_; }
  bool cancelled() const { return cancelled_; }

 private:
  void run() {
    // A signal handler cannot notify a condition variable, so cancel is polled every 5 ms.
    constexpr auto kPoll = std::chrono::milliseconds(5);
    std::unique_lock lock(mutex_);
    while (!finished_) {
      if (cancel_ && cancel_->load()) {
        cancelled_ = true;
        break;
      }
      const auto now = Clock::now();
      if (deadline_ && now >= *deadline_) {
        deadline_reached_ = true;
        break;
      }
      cv_.wait_until(lock, deadline_ ? std::min(now + kPoll, *deadline_) : now + kPoll);
    }
    if (!finished_) stop_.store(true);
  }

  std::atomic<bool>& stop_;
  const std::atomic<bool>* cancel_;
  std::optional<Clock::time_point> deadline_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool finished_ = false;
  bool deadline_reached_ = false, cancelled_ = false;
  std::thread thread_;
};

}  // namespace

bool renders_pixel(const Film& film, const RenderSettings& options, Vec2i p) {
  const int ts = std::max(1, options.tile_size);
  const Vec2i q = p - film.origin();
  const int tiles_x = (film.width() + ts - 1) / ts;
  const int i = (q.y / ts) * tiles_x + q.x / ts;
  return i % std::max(1, options.tile_ranks) == options.tile_rank;
}

uint32_t sampler_seed(const RenderSettings& options) {
  return static_cast<uint32_t>(options.seed ^ (options.seed >> 32));
}

Ray camera_sample(const Scene& scene, const PixelFilter& filter, Sampler& sampler, int x, int y, int s) {
  sampler.start(static_cast<uint32_t>(x), static_cast<uint32_t>(y), static_cast<uint32_t>(s));
  const Vec4 u = sampler.next_4d();  // pixel filter (x, y), lens (z, w)
  const Vec2 offset = filter.sample(Vec2(u.x, u.y));
  // Under a shutter, one more dimension picks the time (only then, so stills keep their sample streams).
  const std::vector<Camera>& shutter = scene.shutter_cameras;
  const Camera& cam =
      shutter.empty() ? scene.camera
                      : shutter[std::min(shutter.size() - 1, static_cast<size_t>(sampler.next_1d() * shutter.size()))];
  return cam.generate_ray(Vec2(x + 0.5f, y + 0.5f) + offset, Vec2(u.z, u.w));
}

bool sample_counts(const Rgb& L, bool signed_samples) {
  return is_finite(L) && (signed_samples || (L.r >= 0.0f && L.g >= 0.0f && L.b >= 0.0f));
}

float clamp_factor(const Rgb& L, float clamp) {
  if (!(clamp > 0.0f)) return 1.0f;
  const float m = std::max({std::abs(L.r), std::abs(L.g), std::abs(L.b)});
  return m > clamp ? clamp / m : 1.0f;
}

std::optional<Rgb> visible_emission_sample(const Scene& scene, const Integrator& integrator, const PixelFilter& filter,
                                           const RenderSettings& options, RenderThreadState& st, int x, int y, int s,
                                           const StopFlag& stop) {
  const Ray ray = camera_sample(scene, filter, st.sampler, x, y, s);
  const Rgb e = integrator.visible_emission(ray, st.sampler, st.arena, st.rays, stop);
  st.arena.reset();
  if (!sample_counts(e, integrator.signed_samples())) return std::nullopt;
  return e * clamp_factor(e, options.clamp);
}

int max_render_threads() { return 4 * std::max(1, static_cast<int>(std::thread::hardware_concurrency())); }

int render_threads(const RenderSettings& options) {
  return std::clamp(options.threads > 0 ? options.threads : static_cast<int>(tbb::info::default_concurrency()), 1,
                    max_render_threads());
}

// The squared deviations of a pixel's n values from their own mean, from their sum and sum of squares.
static double deviations(float sum, float sum2, float n) { return double(sum2) - double(sum) * sum / n; }

double pixel_memory_variance(const std::vector<const PixelMemory*>& memories) {
  double ss = 0.0, dof = 0.0;
  for (const PixelMemory* m : memories)
    if (m && m->samples >= 2.0f) {
      ss += deviations(m->sum, m->sum2, m->samples);
      dof += m->samples - 1.0;
    }
  return dof > 0.0 ? std::max(ss / dof, 0.0) : 0.0;
}

void pool_pixel_memory(std::span<PixelMemory> memory, int width, int height, double image_variance,
                       const std::function<const PixelMemory*(int x, int y)>& other) {
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y != rows.end(); ++y)
      for (int x = 0; x < width; ++x) {
        uint32_t light = 0;
        bool same = true;
        float seen = 0.0f, all = 0.0f;
        double removed_ss = 0.0, dof = 0.0;  // what the control variate removed from the neighbours' squared deviations
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if (dx == 0 && dy == 0) continue;
            const PixelMemory* o = other ? other(nx, ny) : nullptr;
            if (!o && (nx < 0 || ny < 0 || nx >= width || ny >= height)) continue;
            const PixelMemory& m = o ? *o : memory[size_t(ny) * size_t(width) + size_t(nx)];
            if (m.cv_samples >= 2.0f) {
              removed_ss += deviations(m.without_sum, m.without_sum2, m.cv_samples) -
                            deviations(m.with_sum, m.with_sum2, m.cv_samples);
              dof += m.cv_samples - 1.0;
            }
            if (!m.light) continue;
            same = same && (!light || light == m.light);
            light = m.light;
            seen += m.seen;
            all += m.all;
          }
        PixelMemory& m = memory[size_t(y) * size_t(width) + size_t(x)];
        const bool learnt = same && light && all > 0.0f;
        m.learnt_light = learnt ? light : 0;
        m.learnt_share = learnt ? std::min(seen / all, 1.0f) : 0.0f;
        // The variance the control variate removed within the neighbours' pixels (not between them, which edges
        // make and no sample changes), against what its cost would buy the image elsewhere (PixelMemory::kCost).
        m.learnt_skip = dof > 0.0 && image_variance > 0.0 && removed_ss < PixelMemory::kCost * image_variance * dof;
      }
  });
}

namespace {

// This rank's tiles of the film's window (every tile_ranks-th, from tile_rank).
std::vector<Tile> rank_tiles(const Film& film, const RenderSettings& options) {
  const Vec2i lo = film.origin(), hi = film.origin() + Vec2i(film.width(), film.height());
  std::vector<Tile> tiles;
  const int ts = std::max(1, options.tile_size);
  for (int y = lo.y, i = 0; y < hi.y; y += ts)
    for (int x = lo.x; x < hi.x; x += ts, ++i)
      if (i % std::max(1, options.tile_ranks) == options.tile_rank)
        tiles.push_back({x, y, std::min(x + ts, hi.x), std::min(y + ts, hi.y)});
  return tiles;
}

// The most samples any pixel of the tiles holds.
uint64_t most_taken(const Film& film, const std::vector<Tile>& tiles) {
  uint64_t most = 0;
  for (const Tile& t : tiles)
    for (int y = t.y0; y < t.y1; ++y)
      for (int x = t.x0; x < t.x1; ++x) most = std::max<uint64_t>(most, film.taken(x, y));
  return most;
}

// The fewest samples any pixel of the tiles holds (0 for none).
uint64_t fewest_taken(const Film& film, const std::vector<Tile>& tiles) {
  uint64_t fewest = std::numeric_limits<uint32_t>::max();
  for (const Tile& t : tiles)
    for (int y = t.y0; y < t.y1; ++y)
      for (int x = t.x0; x < t.x1; ++x) fewest = std::min<uint64_t>(fewest, film.taken(x, y));
  return tiles.empty() ? 0 : fewest;
}

// One sample of one pixel, into the film.
struct PixelSampler {
  const Scene& scene;
  const Integrator& integrator;
  const PixelFilter& filter;
  Film& film;
  const RenderSettings& options;
  const std::atomic<bool>& stop;
  bool signed_samples;
  // One per pixel of the film's window where the integrator learns from the neighbouring pixels' samples (empty:
  // none).
  std::span<PixelMemory> memory;

  // Sample s of pixel (x, y); false when the stop flag was raised (the sample, possibly cut short, is dropped so
  // that every pixel is the mean of complete samples).
  bool sample(ThreadState& st, int x, int y, int s) const {
    if (stop.load(std::memory_order_relaxed)) return false;
    const Ray ray = camera_sample(scene, filter, st.sampler, x, y, s);
    PixelFeatures features;
    const bool apart = film.emission_apart(x, y);
    PixelMemory* remembered =
        memory.empty() ? nullptr
                       : &memory[size_t(y - film.origin().y) * size_t(film.width()) + size_t(x - film.origin().x)];
    // A dropped sample teaches nothing either: the memory holds what the film's samples saw, as a checkpoint
    // carries both.
    const PixelMemory before = remembered ? *remembered : PixelMemory{};
    Rgb L = integrator.li_pixel(ray, st.sampler, st.arena, st.rays, stop,
                                film.has_features() || apart ? &features : nullptr, remembered);
    st.arena.reset();
    if (stop.load(std::memory_order_relaxed)) {
      if (remembered) *remembered = before;
      return false;
    }
    // Supersampled apart (render/emission_supersampling.h): the film adds the visible emission back. L holds it as a
    // term of its sum, so the difference is the rest up to rounding, which must not make a sample negative.
    if (apart) L = integrator.signed_samples() ? L - features.emission : glm::max(L - features.emission, Rgb(0.0f));
    ++st.paths;
    // Non-finite samples are discarded and counted, never written; so are negative ones, unless the integrator's
    // estimates may rightly be negative (Integrator::signed_samples).
    const bool valid = sample_counts(L, signed_samples);
    // render.clamp: the sample scaled, not cut per channel, so a clamped firefly keeps its hue; its visible emission
    // is still the same share of it.
    if (valid) {
      const float k = clamp_factor(L, options.clamp);
      L *= k;
      features.emission *= k;
    } else {
      features.emission = Rgb(0.0f);  // the film keeps only what its samples hold
    }
    if (film.has_features()) film.add_features(x, y, features, valid && s % 2 == 0 ? &L : nullptr);
    // Coverage (--alpha): whether the camera ray meets any geometry, for the samples that count.
    if (valid && film.has_alpha() && scene.camera_hits(ray)) film.add_hit(x, y);
    if (valid)
      film.add_sample(x, y, L);
    else
      film.add_discarded(x, y);
    return true;
  }
};

}  // namespace

std::optional<Clock::time_point> render_deadline(const RenderSettings& options, const RenderProgress* progress,
                                                 Clock::time_point start) {
  std::optional<Clock::time_point> deadline;
  if (options.time_limit > 0.0)
    deadline = start + std::chrono::duration_cast<Clock::duration>(
                           std::chrono::duration<double>(std::min(options.time_limit, RenderSettings::kMaxTimeLimit)));
  if (progress && progress->deadline)
    deadline = deadline ? std::min(*deadline, *progress->deadline) : *progress->deadline;
  return deadline;
}

RenderResult render(const Scene& scene, const Integrator& integrator, Film& film, const RenderSettings& options,
                    RenderProgress* progress, const PassHook& hook) {
  const PixelFilter filter(options.filter);
  const uint32_t seed32 = sampler_seed(options);

  const std::vector<Tile> tiles = rank_tiles(film, options);
  // Each pixel goes on from the samples the film holds (a resumed checkpoint): sample begin + taken is its next.
  const int begin = std::max(0, options.sample_begin);
  const uint64_t fewest = fewest_taken(film, tiles);

  const int threads = render_threads(options);
  // TBB caps its workers at the hardware's thread count unless told otherwise.
  tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
  tbb::task_arena arena(threads);
  tbb::enumerable_thread_specific<ThreadState> states([&] { return ThreadState(seed32); });

  const auto start = Clock::now();
  std::atomic<bool> stop{false};
  const std::optional<Clock::time_point> deadline = render_deadline(options, progress, start);
  Watchdog watchdog(stop, progress ? &progress->cancel : nullptr, deadline);
  const int target = options.spp > 0 ? options.spp : std::numeric_limits<int>::max();

  // The visible emission supersampled apart, decided once per film before its first sample (a film with samples,
  // a resumed checkpoint's, keeps what its render decided: none, as checkpoints turn it off).
  EmissionSupersamplingStats emission;
  if (emission_supersampling_applies(film, options, {}, deadline.has_value()))
    arena.execute([&] {
      film.set_emission_apart(supersample_emission(scene, integrator, film, options, stop, {}, &emission, deadline));
    });

  // Each pixel's memory lives in the film, so that a checkpoint carries it and a render resumed from one continues it
  // (the same image bit for bit). A split render's pixels (--crop, --sample-range, MPI ranks) begin knowing nothing
  // of their neighbours outside, which changes their noise, not their mean (PixelMemory).
  if (integrator.pixel_memory() && !film.has_memory()) film.enable_memory();
  const std::span<PixelMemory> memory =
      integrator.pixel_memory() ? std::span<PixelMemory>(film.memory()) : std::span<PixelMemory>();
  const PixelSampler pixel{scene, integrator, filter, film, options, stop, integrator.signed_samples(), memory};
  // Adaptive sampling (render.noise_threshold, render/adaptive_sampling.h): pixels found converged between passes
  // take no more samples.
  std::optional<AdaptiveSampling> adaptive;
  if (options.noise_threshold > 0.0f)
    adaptive.emplace(film, options.noise_threshold, options.min_spp,
                     [&](Vec2i p) { return renders_pixel(film, options, p); });
  // Samples s0 .. s1-1 of the tile's pixels; in the first pass (level >= 0) only the pixels of that level.
  auto render_tile = [&](const Tile& t, int s0, int s1, int level) {
    ThreadState& st = states.local();
    for (int s = s0; s < s1; ++s) {
      uint64_t taken = 0;
      bool go_on = true;
      for (int y = t.y0; y < t.y1 && go_on; ++y)
        for (int x = t.x0; x < t.x1 && go_on; ++x) {
          if (level >= 0 && !in_level(x, y, level)) continue;
          if (adaptive && adaptive->converged(x, y)) continue;
          if (static_cast<int64_t>(s) < int64_t{begin} + film.taken(x, y)) continue;  // resumed: already taken
          go_on = pixel.sample(st, x, y, s);
          taken += go_on;
        }
      if (progress) progress->samples_done.fetch_add(taken, std::memory_order_relaxed);
      if (!go_on) return;
    }
  };
  auto run_pass = [&](int s0, int s1, int level) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, tiles.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i) render_tile(tiles[i], s0, s1, level);
    });
  };

  // The hook runs between passes once its interval has passed; passes are cut so that one lasts about a quarter
  // of the interval, from the time per sample of the last one.
  auto last_hook = Clock::now();
  double seconds_per_sample = 0.0;  // of one pass over the window, measured
  auto after_pass = [&] {
    if (hook.interval > 0.0 && hook.every && !stop.load() &&
        std::chrono::duration<double>(Clock::now() - last_hook).count() >= hook.interval) {
      hook.every();
      last_hook = Clock::now();
    }
  };
  // "ltc"'s pixel memories are pooled once (PixelMemory), when every pixel of the window has taken kPilotSamples
  // (passes are cut there, below). What a pixel learns depends on its neighbours' pilot samples and the lattice's
  // (pixel_memory_variance) alone, which a part of a split render traces again where its film does not hold them:
  // the pixels around its tiles (a crop's window, other ranks' tiles) and the lattice outside them, here, and its own
  // pixels' samples before its range (--sample-range), at its start. Not after a pass the stop cut short: a resumed
  // render pools once the pass is whole, as one never stopped did (the film remembers whether it pooled, and a
  // checkpoint carries that).
  const int pilot = PixelMemory::kPilotSamples;
  const Vec2i image = scene.camera.resolution();
  const auto in_window = [&](int x, int y) {
    const Vec2i q = Vec2i(x, y) - film.origin();
    return q.x >= 0 && q.y >= 0 && q.x < film.width() && q.y < film.height();
  };
  const auto mine = [&](int x, int y) { return in_window(x, y) && renders_pixel(film, options, Vec2i(x, y)); };
  const auto memory_at = [&](int x, int y) -> PixelMemory& {
    return memory[size_t(y - film.origin().y) * size_t(film.width()) + size_t(x - film.origin().x)];
  };
  // Samples [s0, s1) of each pixel into its memory alone, nothing into the film; false when the stop cut them short.
  const auto trace_pilots = [&](const std::vector<std::pair<Vec2i, PixelMemory*>>& pixels, int s0, int s1) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, pixels.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
      ThreadState& st = states.local();
      for (size_t i = r.begin(); i != r.end(); ++i)
        for (int s = s0; s < s1; ++s) {
          if (stop.load(std::memory_order_relaxed)) return;
          const auto [p, m] = pixels[i];
          const Ray ray = camera_sample(scene, filter, st.sampler, p.x, p.y, s);
          integrator.li_pixel(ray, st.sampler, st.arena, st.rays, stop, nullptr, m);
          st.arena.reset();
        }
    });
    return !stop.load();
  };
  auto pool_if_due = [&](int done) {
    if (memory.empty() || done < pilot || stop.load() || film.memory_pooled_at() > 0) return;
    // The pilots of the pixels this render does not sample that the pool reads: around its own, and the lattice's.
    std::unordered_map<uint64_t, PixelMemory> others;
    const auto key = [](int x, int y) { return (uint64_t(uint32_t(x)) << 32) | uint32_t(y); };
    const auto in_image = [&](int x, int y) { return x >= 0 && y >= 0 && x < image.x && y < image.y; };
    const Vec2i lo = film.origin(), hi = film.origin() + Vec2i(film.width(), film.height());
    for (int y = lo.y - 1; y <= hi.y; ++y)
      for (int x = lo.x - 1; x <= hi.x; ++x) {
        if (!in_image(x, y) || mine(x, y)) continue;
        bool near = false;
        for (int dy = -1; dy <= 1 && !near; ++dy)
          for (int dx = -1; dx <= 1 && !near; ++dx) near = mine(x + dx, y + dy);
        if (near) others.try_emplace(key(x, y));
      }
    // The lattice's memories, in image order (an unordered_map's elements stay where they are as it grows).
    std::vector<const PixelMemory*> lattice;
    for (int y = 0; y < image.y; y += kPixelMemoryLattice)
      for (int x = 0; x < image.x; x += kPixelMemoryLattice)
        lattice.push_back(mine(x, y) ? &memory_at(x, y) : &others.try_emplace(key(x, y)).first->second);
    std::vector<std::pair<Vec2i, PixelMemory*>> pilots;
    pilots.reserve(others.size());
    for (auto& [k, m] : others) pilots.push_back({Vec2i(int(k >> 32), int(uint32_t(k))), &m});
    if (!trace_pilots(pilots, 0, pilot)) return;
    static const PixelMemory none;  // outside the image: no neighbour
    const auto other = [&](int x, int y) -> const PixelMemory* {
      const int ix = x + film.origin().x, iy = y + film.origin().y;
      if (mine(ix, iy)) return nullptr;
      const auto it = others.find(key(ix, iy));
      return it == others.end() ? &none : &it->second;
    };
    pool_pixel_memory(memory, film.width(), film.height(), pixel_memory_variance(lattice), other);
    film.set_memory_pooled_at(done);
  };
  arena.execute([&] {
    const int first = static_cast<int>(std::min<int64_t>(int64_t{begin} + static_cast<int64_t>(fewest), target));
    int done = first;
    // A part of the samples that begins after the first (--sample-range): its pixels' pilot samples before its
    // range, into their memories alone, before its own samples add to them (as in the whole render's order). Again
    // after a stop that left no sample in the film.
    if (!memory.empty() && begin > 0 && film.memory_pooled_at() == 0 && most_taken(film, tiles) == 0) {
      std::vector<std::pair<Vec2i, PixelMemory*>> own;
      for (const Tile& t : tiles)
        for (int y = t.y0; y < t.y1; ++y)
          for (int x = t.x0; x < t.x1; ++x) {
            memory_at(x, y) = PixelMemory{};
            own.push_back({Vec2i(x, y), &memory_at(x, y)});
          }
      trace_pilots(own, 0, std::min(begin, pilot));
    }
    pool_if_due(done);  // a resumed film whose pilot pass the stop cut short, or a range after the pilots
    if (done < target) {
      // The first sample of this render, coarse to fine.
      for (int level = 0; level < kFirstPassLevels && !stop.load(); ++level) run_pass(done, done + 1, level);
      ++done;
      pool_if_due(done);
      after_pass();
    }
    // A resumed film's converged pixels stay converged.
    bool all_converged = adaptive && adaptive->update(film);
    while (done < target && !stop.load() && !all_converged) {
      // A pass adds half as many samples as were taken so far, between 1 and 16 (1, 1, 1, 1, 2, 3,
      // 4, 6, 9, 14, 16, ...): a stop at any time leaves pixel counts within one pass of each
      // other, and per-pass overhead stays small even for tiny images.
      int pass = std::min(target - done,
                          options.pass_samples > 0 ? options.pass_samples : std::clamp((done - begin) / 2, 1, 16));
      if (hook.interval > 0.0 && seconds_per_sample > 0.0)
        pass = static_cast<int>(std::clamp(0.25 * hook.interval / seconds_per_sample, 1.0, static_cast<double>(pass)));
      // Pixel memories are pooled after the pilot samples, whatever the passes (so the image does not depend on them).
      if (!memory.empty() && done < pilot) pass = std::min(pass, pilot - done);
      const auto t = Clock::now();
      run_pass(done, done + pass, -1);
      seconds_per_sample = std::chrono::duration<double>(Clock::now() - t).count() / pass;
      done += pass;
      pool_if_due(done);
      if (adaptive) all_converged = adaptive->update(film);
      after_pass();
    }
  });
  watchdog.finish();

  RenderResult result;
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  for (const PixelMemory& m : memory)
    if (m.samples > 0.0f) {
      ++result.control_variate.pixels;
      result.control_variate.pixels_taking += m.cv_samples > 0.0f && !m.learnt_skip;
      result.control_variate.samples += m.samples;
      result.control_variate.samples_taking += m.cv_samples;
    }
  result.hit_time_limit = watchdog.deadline_reached();
  result.cancelled = watchdog.cancelled();
  result.threads = arena.max_concurrency();
  for (const ThreadState& st : states) {
    result.rays += st.rays;
    result.paths += st.paths;
  }
  result.rays += emission.rays;
  result.emission = emission;
  result.film = film.summary();
  return result;
}

}  // namespace kozu
