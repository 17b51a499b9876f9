// Rays/s of the path tracer as a fraction of Embree's own on the very same rays, for any scenes (docs/performance.md,
// "The machine's limit"), and whether Embree's stream queries trace the camera rays faster than one query per ray.
//
//   build/bench/bench_rays [--width 256] [--spp 4] [SCENE.json ...] [--benchmark_repetitions=3 ...]
//
// Without scenes: the built-in demo and scenes/cornell.json. Each scene is rendered at --width pixels across (its
// aspect kept). Benchmarks, per scene:
//   path/SCENE/threads:T    a render of --spp samples per pixel on T threads: samples/s and rays/s (every ray the
//                           render traced, as `kozu render --stats` counts them);
//   embree/SCENE/threads:T  the same rays, recorded from a single-threaded render, replayed through rtcIntersect1
//                           and rtcOccluded1 alone (no shading, no sampling), split across T threads in chunks;
//   camera/SCENE/single     the camera's rays alone (spp jittered rays per pixel in scanline order, as the renderer
//                           traces a pixel's samples), one rtcIntersect1 per ray, coherent flag;
//   camera/SCENE/stream     the same through rtcIntersect1M, 64 rays per call, coherent flag.
// Then one table: the path tracer's rays/s over Embree's, per scene and thread count, and the stream's rate over the
// single queries' (medians over repetitions).
#include "bench_support.h"
#include "integrators/path.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>
#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <random>
#include <memory>
#include <string>
#include <vector>

namespace kozu {
namespace {

struct BenchScene {
  std::string name;
  std::unique_ptr<Scene> scene;
  RayLog log;
  std::vector<Ray> camera_rays;
  uint64_t recorded_render_rays = 0;  // what the recording render counted, against the log's size
};

int g_spp = 4;
std::map<std::string, std::vector<double>> g_rates;  // "kind/scene/threads" -> rays/s of each repetition

using bench::ray_hit;
using bench::trace_closest;
using bench::trace_shadow;

// Records the rays of a single-threaded render of the scene, and picks out its camera rays.
void record(BenchScene& b) {
  PathIntegrator integrator(*b.scene, b.scene->settings.max_depth);
  RenderSettings opt;
  opt.spp = g_spp;
  opt.threads = 1;
  const Vec2i res = b.scene->camera.resolution();
  Film film(res.x, res.y);
  b.scene->set_ray_log(&b.log);
  const RenderResult r = render(*b.scene, integrator, film, opt);
  b.scene->set_ray_log(nullptr);
  b.recorded_render_rays = r.rays.total();
  // The camera rays, in scanline order with spp jittered rays per pixel (lens points for a thin lens).
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int y = 0; y < res.y; ++y)
    for (int x = 0; x < res.x; ++x)
      for (int s = 0; s < g_spp; ++s)
        b.camera_rays.push_back(b.scene->camera.generate_ray(Vec2(x + u(rng), y + u(rng)), Vec2(u(rng), u(rng))));
}

void bm_path(benchmark::State& state, BenchScene* b, int threads) {
  const double rate = bench::measure_renders(state, *b->scene, threads, g_spp, b->scene->camera.resolution());
  g_rates[fmt::format("path/{}/{}", b->name, threads)].push_back(rate);
}

void bm_embree(benchmark::State& state, BenchScene* b, int threads) {
  const RTCScene handle = b->scene->accel().handle();
  tbb::task_arena arena(threads);
  const std::vector<Ray>& closest = b->log.closest;
  const std::vector<Ray>& shadow = b->log.shadow;
  double seconds = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, closest.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) trace_closest(handle, closest[i], RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT);
      });
      tbb::parallel_for(tbb::blocked_range<size_t>(0, shadow.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) trace_shadow(handle, shadow[i]);
      });
    });
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    state.SetIterationTime(s);
    seconds += s;
  }
  const double rays = static_cast<double>(closest.size() + shadow.size()) * static_cast<double>(state.iterations());
  state.counters["rays_per_s"] = rays / seconds;
  g_rates[fmt::format("embree/{}/{}", b->name, threads)].push_back(rays / seconds);
}

void bm_camera(benchmark::State& state, BenchScene* b, bool stream) {
  const RTCScene handle = b->scene->accel().handle();
  const std::vector<Ray>& rays = b->camera_rays;
  constexpr size_t kStream = 64;
  std::vector<RTCRayHit> batch(kStream);
  double seconds = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    if (stream) {
      RTCIntersectContext ctx;
      rtcInitIntersectContext(&ctx);
      ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
      for (size_t i = 0; i < rays.size(); i += kStream) {
        const size_t n = std::min(kStream, rays.size() - i);
        for (size_t j = 0; j < n; ++j) batch[j] = ray_hit(rays[i + j]);
        rtcIntersect1M(handle, &ctx, batch.data(), static_cast<unsigned>(n), sizeof(RTCRayHit));
        benchmark::DoNotOptimize(batch[0].hit.geomID);
      }
    } else {
      for (const Ray& ray : rays) trace_closest(handle, ray, RTC_INTERSECT_CONTEXT_FLAG_COHERENT);
    }
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    state.SetIterationTime(s);
    seconds += s;
  }
  const double n = static_cast<double>(rays.size()) * static_cast<double>(state.iterations());
  state.counters["rays_per_s"] = n / seconds;
  g_rates[fmt::format("camera/{}/{}", b->name, stream ? "stream" : "single")].push_back(n / seconds);
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace
}  // namespace kozu

int main(int argc, char** argv) {
  using namespace kozu;
  int width = 256;
  std::vector<std::string> files;
  std::vector<char*> bench_args{argv[0]};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if ((a == "--width" || a == "--spp") && i + 1 < argc) {
      (a == "--width" ? width : g_spp) = std::max(1, std::atoi(argv[++i]));
    } else if (a.rfind("--", 0) == 0) {
      bench_args.push_back(argv[i]);
    } else {
      files.push_back(a);
    }
  }
  if (files.empty()) files = {"demo", std::string(KOZU_SOURCE_DIR) + "/scenes/cornell.json"};
  int bench_argc = static_cast<int>(bench_args.size());
  benchmark::Initialize(&bench_argc, bench_args.data());

  std::vector<std::unique_ptr<BenchScene>> scenes;
  for (const std::string& f : files) {
    auto b = std::make_unique<BenchScene>();
    b->name = f == "demo" ? "demo" : std::filesystem::path(f).stem().string();
    b->scene = f == "demo" ? load_demo_scene() : load_scene_file(f);
    const Vec2i res = b->scene->camera.resolution();
    b->scene->camera.set_resolution(Vec2i(width, std::max(1, width * res.y / std::max(1, res.x))));
    record(*b);
    BenchScene* p = b.get();
    for (const int threads : {1, 2}) {
      benchmark::RegisterBenchmark(fmt::format("path/{}/threads:{}", p->name, threads).c_str(), bm_path, p, threads)
          ->UseManualTime()
          ->Unit(benchmark::kMillisecond)
          ->MinTime(1.0);
      benchmark::RegisterBenchmark(fmt::format("embree/{}/threads:{}", p->name, threads).c_str(), bm_embree, p,
                                   threads)
          ->UseManualTime()
          ->Unit(benchmark::kMillisecond)
          ->MinTime(1.0);
    }
    for (const bool stream : {false, true})
      benchmark::RegisterBenchmark(fmt::format("camera/{}/{}", p->name, stream ? "stream" : "single").c_str(),
                                   bm_camera, p, stream)
          ->UseManualTime()
          ->Unit(benchmark::kMillisecond)
          ->MinTime(0.5);
    scenes.push_back(std::move(b));
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();

  fmt::print("\n| scene | threads | path tracer rays/s | Embree alone rays/s | fraction | rays recorded / counted |\n");
  fmt::print("| --- | ---: | ---: | ---: | ---: | ---: |\n");
  for (const auto& b : scenes)
    for (const int threads : {1, 2}) {
      const double path = median(g_rates[fmt::format("path/{}/{}", b->name, threads)]);
      const double raw = median(g_rates[fmt::format("embree/{}/{}", b->name, threads)]);
      if (path <= 0.0 || raw <= 0.0) continue;
      fmt::print("| {} | {} | {:.3g} M | {:.3g} M | {:.0f} % | {} / {} |\n", b->name, threads, path * 1e-6, raw * 1e-6,
                 100.0 * path / raw, b->log.closest.size() + b->log.shadow.size(), b->recorded_render_rays);
    }
  fmt::print("\n| scene | camera rays | one query per ray, rays/s | stream of 64, rays/s | stream / single |\n");
  fmt::print("| --- | ---: | ---: | ---: | ---: |\n");
  for (const auto& b : scenes) {
    const double single = median(g_rates[fmt::format("camera/{}/single", b->name)]);
    const double stream = median(g_rates[fmt::format("camera/{}/stream", b->name)]);
    if (single <= 0.0 || stream <= 0.0) continue;
    fmt::print("| {} | {} | {:.3g} M | {:.3g} M | {:.2f} |\n", b->name, b->camera_rays.size(), single * 1e-6,
               stream * 1e-6, stream / single);
  }
  return 0;
}
