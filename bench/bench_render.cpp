// Renderer throughput: samples/s and rays/s of the path tracer on the demo scene and the Cornell
// box at 512x512, and Embree's own throughput on the very same rays (recorded from a render and
// replayed with rtcIntersect1/rtcOccluded1), so the path tracer's rate can be stated as a fraction
// of Embree's. Thread counts 1 and 2 give the scaling. BM_Volume: samples/s of the volume showcase's
// bush at 320x240 (docs/volumes.md), as a mesh and as an SGGX volume (auto LOD, level 0 and level 2);
// the volume is voxelized in process from scenes/meshes/bush.ply at 128, as `kozu voxelize` does.
//
//   build/bench/bench_render --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include "bench_support.h"
#include "core/file_io.h"
#include "integrators/path.h"
#include "io/mesh_io.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "tools/voxelize.h"

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <unistd.h>

#include <filesystem>
#include <map>
#include <memory>
#include <mutex>

namespace kozu {
namespace {

constexpr int kResolution = 512;
constexpr int kSppPerIteration = 4;

const Scene& get_scene(const std::string& name) {
  static std::map<std::string, std::unique_ptr<Scene>> cache;
  static std::mutex mutex;
  std::lock_guard lock(mutex);
  auto& s = cache[name];
  if (!s) {
    s = name == "demo" ? load_demo_scene()
                       : load_scene_file(std::string(KOZU_SOURCE_DIR) + "/scenes/" + name + ".json");
    s->camera.set_resolution(Vec2i(kResolution, kResolution));
  }
  return *s;
}

const char* scene_name(int64_t i) { return i == 0 ? "demo" : "cornell"; }

// Renders kSppPerIteration per iteration and reports samples/s and rays/s over all iterations.
void measure_renders(benchmark::State& state, const Scene& scene, int threads, Vec2i resolution, const char* label) {
  bench::measure_renders(state, scene, threads, kSppPerIteration, resolution);
  state.SetLabel(label);
}

void BM_PathTracer(benchmark::State& state) {
  measure_renders(state, get_scene(scene_name(state.range(0))), static_cast<int>(state.range(1)), Vec2i(kResolution),
                  scene_name(state.range(0)));
}
BENCHMARK(BM_PathTracer)
    ->ArgsProduct({{0, 1}, {1, 2}})
    ->ArgNames({"scene", "threads"})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

// ---- volumes ------------------------------------------------------------------------------------------

constexpr Vec2i kVolumeResolution{320, 240};

const char* volume_case(int64_t i) {
  static const char* names[] = {"bush mesh", "bush SGGX auto LOD", "bush SGGX LOD 0", "bush SGGX LOD 2"};
  return names[i];
}

const Scene& get_volume_scene(int64_t i) {
  static std::map<int64_t, std::unique_ptr<Scene>> cache;
  auto& s = cache[i];
  if (s) return *s;
  const std::filesystem::path scenes = std::filesystem::path(KOZU_SOURCE_DIR) / "scenes";
  if (i == 0) {
    s = load_scene_file(scenes / "bush_mesh.json");
  } else {
    // bush_volume.json reads volumes/bush.kvox next to itself: write it into a scratch directory.
    const std::filesystem::path dir =
        std::filesystem::temp_directory_path() / ("kozu_bench_volume_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir / "volumes");
    voxelize_mesh(load_mesh(scenes / "meshes" / "bush.ply"), 128).save_kvox(dir / "volumes" / "bush.kvox");
    std::string json = read_input_file(scenes / "bush_volume.json");
    if (i > 1) {
      const std::string key = "\"phase\": \"diffuse\"";
      json.replace(json.find(key), key.size(), key + (i == 2 ? ", \"lod\": 0" : ", \"lod\": 2"));
    }
    s = load_scene_text(json, "bush_volume.json", dir);
    std::filesystem::remove_all(dir);
  }
  s->camera.set_resolution(kVolumeResolution);
  s->set_media_view();
  return *s;
}

void BM_Volume(benchmark::State& state) {
  measure_renders(state, get_volume_scene(state.range(0)), static_cast<int>(state.range(1)), kVolumeResolution,
                  volume_case(state.range(0)));
}
BENCHMARK(BM_Volume)
    ->ArgsProduct({{0, 1, 2, 3}, {2}})
    ->ArgNames({"case", "threads"})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

// Rays of one 4-spp render, recorded single-threaded.
struct RecordedRays {
  RayLog log;
};
const RecordedRays& get_rays(const std::string& name) {
  static std::map<std::string, std::unique_ptr<RecordedRays>> cache;
  auto& r = cache[name];
  if (!r) {
    r = std::make_unique<RecordedRays>();
    auto& scene = const_cast<Scene&>(get_scene(name));
    PathIntegrator integrator(scene, scene.settings.max_depth);
    RenderSettings opt;
    opt.spp = kSppPerIteration;
    opt.threads = 1;
    Film film(kResolution, kResolution);
    scene.set_ray_log(&r->log);
    render(scene, integrator, film, opt);
    scene.set_ray_log(nullptr);
  }
  return *r;
}

// Embree alone on the recorded rays, in recording order, split across threads in chunks.
void BM_EmbreeRaw(benchmark::State& state) {
  const std::string name = scene_name(state.range(0));
  const Scene& scene = get_scene(name);
  const RecordedRays& rays = get_rays(name);
  const int threads = static_cast<int>(state.range(1));
  const RTCScene handle = scene.accel().handle();
  tbb::task_arena arena(threads);
  const size_t n_closest = rays.log.closest.size(), n_shadow = rays.log.shadow.size();
  for (auto _ : state) {
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, n_closest, 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) bench::trace_closest(handle, rays.log.closest[i]);
      });
      tbb::parallel_for(tbb::blocked_range<size_t>(0, n_shadow, 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) bench::trace_shadow(handle, rays.log.shadow[i]);
      });
    });
  }
  state.counters["rays_per_s"] =
      benchmark::Counter(static_cast<double>(n_closest + n_shadow) * state.iterations(), benchmark::Counter::kIsRate);
  state.SetLabel(name);
}
BENCHMARK(BM_EmbreeRaw)
    ->ArgsProduct({{0, 1}, {1, 2}})
    ->ArgNames({"scene", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0)
    ->UseRealTime();

}  // namespace
}  // namespace kozu

BENCHMARK_MAIN();
