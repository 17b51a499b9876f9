// The denoisers' cost per pixel (docs/production.md): the feature regression (render/feature_regression.h, the
// default) and the NL-means filter (render/denoiser.h) on a synthetic 1920 x 1080 film of 8 samples per pixel with
// features (a textured floor, a sphere's shading, a shadow edge, noise), on 1 and 2 threads. The counter us/px is
// the wall time per pixel of one run.
//
//   build/bench/bench_denoise --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
#include "core/rng.h"
#include "render/denoiser.h"
#include "render/feature_regression.h"

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <map>

namespace kozu {
namespace {

// A w x (9/16 w) film of 8 samples per pixel: a checker texture (albedo 0.3 and 0.7, 8-pixel squares) on a
// surface whose normal turns across the image, the right 40 % in shadow, uniform noise of ±100 %.
Film make_film(int w) {
  const int h = w * 9 / 16;
  Film film(w, h);
  film.enable_features();
  Pcg32 rng(3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float u = static_cast<float>(x) / w, v = static_cast<float>(y) / h;
      const float albedo = ((x / 8 + y / 8) % 2) ? 0.7f : 0.3f;
      const Vec3 n = glm::normalize(Vec3(u - 0.5f, v - 0.5f, 1.0f));
      const float light = (u > 0.6f ? 0.2f : 1.0f) * std::max(0.0f, n.z);
      for (int s = 0; s < 8; ++s) {
        const Rgb L(albedo * light * 2.0f * rng.next_float());
        PixelFeatures f;
        f.albedo = Rgb(albedo);
        f.normal = n;
        f.depth = 2.0f + v;
        f.set = true;
        film.add_features(x, y, f, s % 2 == 0 ? &L : nullptr);
        film.add_sample(x, y, L);
      }
    }
  return film;
}

const Film& film(int w) {
  static std::map<int, Film> cache;
  auto it = cache.find(w);
  if (it == cache.end()) it = cache.emplace(w, make_film(w)).first;
  return it->second;
}

template <bool kNlMeans>
void BM_Denoise(benchmark::State& state) {
  const int w = static_cast<int>(state.range(0)), h = w * 9 / 16;
  const Film& f = film(w);
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(state.range(1)));
  for (auto _ : state) {
    const auto t = std::chrono::steady_clock::now();
    std::vector<float> out = kNlMeans ? denoise(f) : denoise_regression(f);
    benchmark::DoNotOptimize(out.data());
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    state.SetIterationTime(s);
    state.counters["us/px"] = 1e6 * s / (static_cast<double>(w) * h);
  }
}
BENCHMARK(BM_Denoise<false>)
    ->Name("BM_DenoiseRegression")
    ->ArgsProduct({{480, 1920}, {1, 2}})
    ->ArgNames({"width", "threads"})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);
BENCHMARK(BM_Denoise<true>)
    ->Name("BM_DenoiseNlMeans")
    ->ArgsProduct({{480}, {1, 2}})
    ->ArgNames({"width", "threads"})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

}  // namespace
}  // namespace kozu

BENCHMARK_MAIN();
