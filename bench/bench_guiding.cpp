// Path guiding's per-vertex costs (integrators/guiding_field.h, directional_quadtree.h): finding a point's leaf,
// evaluating a leaf's density at a direction (the cylindrical mapping alone too), and sampling it, on the field learnt
// by a guided render of the Cornell box (256², 64 spp: its training passes), at random points and directions of the
// box. And the render itself, guided and not, for the overhead as a whole.
//
//   build/bench/bench_guiding --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include "core/file_io.h"
#include "core/rng.h"
#include "render/guiding_training.h"
#include "scene/scene_loader.h"

#include <benchmark/benchmark.h>

#include <memory>
#include <vector>

namespace kozu {
namespace {

constexpr int kResolution = 256;

std::unique_ptr<Scene> cornell() {
  const std::filesystem::path dir = std::filesystem::path(KOZU_SOURCE_DIR) / "scenes";
  auto scene = load_scene_text(read_input_file(dir / "cornell.json"), "cornell.json", dir);
  scene->camera.set_resolution(Vec2i(kResolution));
  return scene;
}

struct Learnt {
  std::unique_ptr<Scene> scene = cornell();
  GuidingField field{scene->center(), scene->radius()};
  std::vector<Vec3> points, directions;
  Learnt() {
    PathIntegrator integrator(*scene, 16);
    Film film(kResolution, kResolution);
    RenderSettings opt;
    opt.spp = 64;
    render_guided(*scene, integrator, field, film, opt, nullptr, {}, nullptr);
    Pcg32 rng(1);
    const Vec3 lo = scene->center() - Vec3(scene->radius() * 0.5f);
    for (int i = 0; i < 4096; ++i) {
      points.push_back(lo + scene->radius() * Vec3(rng.next_float(), rng.next_float(), rng.next_float()));
      directions.push_back(DirectionalQuadtree::to_direction(Vec2(rng.next_float(), rng.next_float())));
    }
  }
};

const Learnt& learnt() {
  static const Learnt l;
  return l;
}

void BM_GuidingLeaf(benchmark::State& state) {
  const Learnt& l = learnt();
  size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(l.field.distribution(l.points[i++ & 4095]));
  state.counters["leaves"] = double(l.field.leaves());
}

void BM_GuidingPdf(benchmark::State& state) {
  const Learnt& l = learnt();
  size_t i = 0;
  for (auto _ : state) {
    const DirectionalQuadtree* d = l.field.distribution(l.points[i & 4095]);
    benchmark::DoNotOptimize(d ? d->pdf(l.directions[i & 4095]) : 0.0f);
    ++i;
  }
}

void BM_GuidingCylindricalMapping(benchmark::State& state) {
  const Learnt& l = learnt();
  size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(DirectionalQuadtree::to_square(l.directions[i++ & 4095]));
}

void BM_GuidingSample(benchmark::State& state) {
  const Learnt& l = learnt();
  Pcg32 rng(2);
  size_t i = 0;
  for (auto _ : state) {
    const DirectionalQuadtree* d = l.field.distribution(l.points[i++ & 4095]);
    float pdf = 0.0f;
    if (d) benchmark::DoNotOptimize(d->sample(Vec2(rng.next_float(), rng.next_float()), &pdf));
  }
}

// The Cornell box at 256², 16 spp, 2 threads, guided (training passes included) or not: samples/s.
void BM_GuidingCornell(benchmark::State& state) {
  const bool guiding = state.range(0) != 0;
  auto scene = cornell();
  for (auto _ : state) {
    PathIntegrator integrator(*scene, 16);
    Film film(kResolution, kResolution);
    RenderSettings opt;
    opt.spp = 16;
    opt.threads = 2;
    GuidingField field(scene->center(), scene->radius());
    const RenderResult r = guiding ? render_guided(*scene, integrator, field, film, opt, nullptr, {}, nullptr)
                                   : render(*scene, integrator, film, opt);
    benchmark::DoNotOptimize(r.paths);
  }
  state.counters["samples/s"] =
      benchmark::Counter(double(state.iterations()) * kResolution * kResolution * 16, benchmark::Counter::kIsRate);
}

BENCHMARK(BM_GuidingLeaf);
BENCHMARK(BM_GuidingPdf);
BENCHMARK(BM_GuidingCylindricalMapping);
BENCHMARK(BM_GuidingSample);
BENCHMARK(BM_GuidingCornell)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace kozu

BENCHMARK_MAIN();
