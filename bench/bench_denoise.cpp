// The denoisers' cost per pixel (docs/production.md): the feature regression (render/feature_regression.h)
// and the NL-means filter (render/denoiser.h, the default) on a synthetic 1920 x 1080 film of 8 samples per pixel with
// features (a textured floor, a sphere's shading, a shadow edge, noise), on 1 and 2 threads; and the learned
// denoiser's network (render/learned_denoiser.h, run_unet) at 480 x 270 with random weights of widths 16/32/48/64
// down and 48/32/16 up (the cost depends on the widths only), on 1 and 2 OpenMP threads. The counter us/px is the
// wall time per pixel of one run.
//
//   build/bench/bench_denoise --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
#include "core/rng.h"
#include "render/denoiser.h"
#include "render/feature_regression.h"
#include "render/learned_denoiser.h"

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <array>
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

// Random weights of the given widths (c0..c3 down, d2..d0 up), He-uniform.
// He-uniform random weights, biases 0.01: the network's cost does not depend on what it learnt.
UnetWeights random_unet(const UnetWidths& widths) {
  Pcg32 rng(7);
  UnetWeights wts = unet_layers(widths);
  for (UnetLayer& l : wts.layers) {
    const float a = std::sqrt(6.0f / (9.0f * static_cast<float>(l.in)));
    for (float& v : l.weights) v = a * (2.0f * rng.next_float() - 1.0f);
    l.bias.assign(l.bias.size(), 0.01f);
  }
  return wts;
}

void BM_Unet(benchmark::State& state) {
  const int w = static_cast<int>(state.range(0)), h = w * 9 / 16;
  static const UnetWeights wts = random_unet({16, 32, 48, 64, 48, 32, 16});
  const size_t n = static_cast<size_t>(w) * h;
  std::vector<float> color(3 * n), albedo(3 * n), normal(3 * n);
  Pcg32 rng(11);
  for (size_t i = 0; i < 3 * n; ++i) {
    color[i] = 2.0f * rng.next_float();
    albedo[i] = rng.next_float();
    normal[i] = 2.0f * rng.next_float() - 1.0f;
  }
  UnetSettings s;
  s.threads = static_cast<int>(state.range(1));
  for (auto _ : state) {
    const auto t = std::chrono::steady_clock::now();
    std::vector<float> out = run_unet(wts, w, h, color, albedo, normal, s);
    benchmark::DoNotOptimize(out.data());
    const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    state.SetIterationTime(sec);
    state.counters["us/px"] = 1e6 * sec / static_cast<double>(n);
  }
}
BENCHMARK(BM_Unet)
    ->ArgsProduct({{480}, {1, 2}})
    ->ArgNames({"width", "threads"})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);

}  // namespace
}  // namespace kozu

BENCHMARK_MAIN();
