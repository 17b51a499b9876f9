#include "render/emission_refine.h"

#include "core/arena.h"
#include "render/renderer.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>

namespace kozu {

VisibleEmission::VisibleEmission(const Film& film) : film_(&film), state_(film.pixels().size(), kFilmMean) {
  if (!film.has_features()) throw std::logic_error("VisibleEmission: the film keeps no features");
}

namespace {

// The first entry of a list sorted by pixel at or after pixel i (const or not).
template <class List>
auto entry_at(List& refined, size_t i) {
  return std::lower_bound(refined.begin(), refined.end(), i,
                          [](const std::pair<uint32_t, Vec3>& r, size_t j) { return r.first < j; });
}

}  // namespace

Vec3 VisibleEmission::value(size_t i) const {
  if (state_[i] == kRefined) return entry_at(refined_, i)->second;
  const uint32_t count = film_->pixels()[i].count;
  return count ? film_->emission_sums().get(i).sum / static_cast<float>(count) : Vec3(0.0f);
}

void VisibleEmission::set(size_t i, const Vec3& v) {
  const auto at = entry_at(refined_, i);
  if (at != refined_.end() && at->first == i)
    at->second = v;
  else
    refined_.insert(at, {static_cast<uint32_t>(i), v});
  state_[i] = kRefined;
}

namespace {

// A pixel whose visible emission is too noisy to add back as it is, and the variance of its mean's luminance.
struct Noisy {
  size_t index;
  double variance;
};

// The film's own means, apart where quiet enough; the noisy pixels, the largest variances first.
VisibleEmission from_film(const Film& film, const EmissionRefineSettings& settings, std::vector<Noisy>* noisy) {
  if (!film.has_features()) throw std::logic_error("visible_emission: the film keeps no features");
  const int w = film.width(), h = film.height();
  const size_t n = film.pixels().size();
  VisibleEmission e(film);
  std::vector<float> lum(n, 0.0f);
  for (size_t i = 0; i < n; ++i) {
    const Vec3 v = e.value(i);
    lum[i] = luminance(Rgb(v.x, v.y, v.z));
  }
  const double rel2 = double(settings.relative_error) * settings.relative_error;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      const Film::Pixel& p = film.pixels()[i];
      if (p.count == 0) continue;  // nothing seen: zero, apart
      const double count = p.count, mean = lum[i];
      const double var =
          count < 2.0
              ? 0.0
              : std::max(0.0, (film.emission_sums().get(i).sq / count - mean * mean) * count / (count - 1.0)) / count;
      // A neighbour whose visible emission differs: an edge runs close by, and a pixel whose few samples all fell
      // on one side of it shows no variance (a small highlight missed by every sample). Its variance, had the
      // samples been split over the edge, is at most jump² / 4 per sample.
      double jump = 0.0;
      for (int ny = std::max(0, y - 1); ny <= std::min(h - 1, y + 1); ++ny)
        for (int nx = std::max(0, x - 1); nx <= std::min(w - 1, x + 1); ++nx)
          jump = std::max(jump, std::abs(double(lum[static_cast<size_t>(ny) * w + nx]) - mean));
      const double scale = std::max({std::abs(mean), double(luminance(Rgb(p.sum / count))), 1e-6});
      const double worst = std::max(var, 0.25 * jump * jump / count);
      if (worst > rel2 * scale * scale) {
        e.keep_in_radiance(i);
        noisy->push_back({i, worst});
      }
    }
  // The index breaks ties: the choice is deterministic.
  std::sort(noisy->begin(), noisy->end(), [](const Noisy& a, const Noisy& b) {
    return a.variance != b.variance ? a.variance > b.variance : a.index < b.index;
  });
  return e;
}

}  // namespace

VisibleEmission visible_emission(const Film& film, const EmissionRefineSettings& settings) {
  std::vector<Noisy> noisy;
  return from_film(film, settings, &noisy);
}

VisibleEmission refine_emission(const Scene& scene, const Integrator& integrator, const Film& film,
                                const RenderSettings& options, const EmissionRefineSettings& settings,
                                EmissionRefineStats* stats, const std::function<bool()>& expired) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<Noisy> noisy;
  VisibleEmission out = from_film(film, settings, &noisy);

  // The samples each noisy pixel takes, the largest variances first, within the pass's budget.
  struct Job {
    size_t index;
    int samples;
  };
  std::vector<Job> jobs;
  const double cap = settings.samples_per_pixel * static_cast<double>(out.size());
  double spent = 0.0;
  for (const Noisy& c : noisy) {
    const int64_t k = std::clamp<int64_t>(int64_t{settings.factor} * film.pixels()[c.index].count, settings.min_samples,
                                          std::max(settings.min_samples, settings.max_samples));
    if (spent + static_cast<double>(k) > cap) break;
    spent += static_cast<double>(k);
    jobs.push_back({c.index, static_cast<int>(k)});
  }

  const PixelFilter filter(options.filter);
  const int begin = std::max(0, options.sample_begin);
  const int w = film.width();
  const Vec2i origin = film.origin();
  std::vector<std::optional<Vec3>> refined(jobs.size());
  tbb::enumerable_thread_specific<RenderThreadState> states(
      [seed = sampler_seed(options)] { return RenderThreadState(seed); });
  const StopFlag never{false};
  std::atomic<bool> stopped{false};
  std::atomic<uint64_t> begun{0}, taken{0};  // pixels and samples
  tbb::task_arena arena(render_threads(options));
  arena.execute([&] {
    tbb::parallel_for(size_t{0}, jobs.size(), [&](size_t j) {
      if (expired && (stopped.load(std::memory_order_relaxed) || expired())) {
        stopped = true;
        return;
      }
      ++begun;
      taken += static_cast<uint64_t>(jobs[j].samples);
      RenderThreadState& st = states.local();
      const size_t i = jobs[j].index;
      const int x = origin.x + static_cast<int>(i % w), y = origin.y + static_cast<int>(i / w);
      Vec3d sum(0.0);
      uint32_t valid = 0;
      for (int s = 0; s < jobs[j].samples; ++s)
        if (const auto e = visible_emission_sample(scene, integrator, filter, options, st, x, y, begin + s, never)) {
          sum += Vec3d(e->r, e->g, e->b);
          ++valid;
        }
      if (valid) refined[j] = Vec3(sum / static_cast<double>(valid));
    });
  });
  // In pixel order, so that each goes to the end of the sorted list.
  std::vector<size_t> order(jobs.size());
  for (size_t j = 0; j < order.size(); ++j) order[j] = j;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return jobs[a].index < jobs[b].index; });
  for (const size_t j : order)
    if (refined[j]) out.set(jobs[j].index, *refined[j]);
  if (stats) {
    stats->pixels = begun;
    stats->samples = taken;
    stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return out;
}

}  // namespace kozu
