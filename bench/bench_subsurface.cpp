// Costs of the Christensen–Burley subsurface model: ns per profile evaluation, ns per radius sample
// (eq. 11 inverted in closed form vs by Newton's method, and how far apart the two land), ns and
// Embree queries per probe-ray sample of the second point, and the cost per pixel sample of the
// showcase scene against the same scene with Lambertian materials.
//
//   build-bench/bench/bench_subsurface --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// Inputs are fixed-seed tables built once, outside the timed loops, and cycled through one call per
// iteration (so Time and CPU are ns per call; ns_per_call repeats the CPU figure as a counter):
//   radii     4096 radii drawn from the profile's own sampling (stratified u below kProbeFraction),
//             so eval sees the 1/r peak and the tail in their true proportions
//   u         4096 u uniform in [0, 1), the same table for the closed form and Newton
//   entries   256 points where rays from outside enter the shape (EmbreeScene::intersect), each
//             paired with 4096 Vec4 u of the probe sampling
// Profiles: the showcase's marble (albedo 0.87/0.85/0.82, mfp 0.06/0.05/0.045, searchlight) and, on
// the torus, its jade (0.4/0.8/0.52, mfp 0.12/0.3/0.16).
//
// Rows and counters
//   BM_ProfileEval/{channel,rgb}        NormalizedDiffusion::eval, RgbProfile::eval (three channels)
//   BM_RadiusSample_{ClosedForm,Newton} sample_closed_form(u), sample(u) (Newton); Newton's mean_iterations and
//                                       max_iterations over the same u table (counted outside the
//                                       timed loop so the out-param does not perturb the timing)
//   BM_RadiusSample_NewtonVsClosed      both on the same u in interleaved blocks timed by thread CPU
//                                       time (order alternating): newton/closed, robust to load drift
//   BM_RadiusSample_Agreement           no timing: over 1e6 stratified u plus the two ends (u down to
//                                       2^-40, the 4096 floats below 1), max_rel_diff =
//                                       max |r_closed − r_newton| / max(r_closed, d), n_differ (u where
//                                       the two floats differ), each method's max |cdf(r) − u| (double)
//   BM_ProbeSample/{sphere,torus}_...   sample_probe: ns per call, probe_rays per sample (Embree
//                                       queries), hit_fraction (calls that return a point)
//   BM_ShowcaseScene/<scene>            scenes/subsurface.json and subsurface_lambert.json at
//                                       320x180, 4 spp per iteration, 2 threads: samples_per_s,
//                                       rays_per_s, rays_per_sample
//   BM_ShowcaseCostRatio                the two scenes rendered alternately in one loop (order
//                                       alternating per iteration), each timed by RenderResult::seconds:
//                                       cost_ratio = (s per sample, subsurface) / (s per sample, lambert)
// On the shared machine prefer the CPU column and the in-run ratios over comparing separate rows.
#include "bssrdf/normalized_diffusion.h"
#include "bssrdf/probe_sampling.h"
#include "core/rng.h"
#include "core/warp.h"
#include "geometry/embree_scene.h"
#include "geometry/shape.h"
#include "integrators/path.h"
#include "io/mesh_io.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace kozu {
namespace {

constexpr size_t kInputs = 4096;  // power of two: indices wrap with a mask
constexpr size_t kMask = kInputs - 1;
constexpr size_t kEntries = 256;

const auto kSearchlight = SubsurfaceParameterization::Searchlight;

RgbProfile marble() {
  return RgbProfile({NormalizedDiffusion::from_length(kSearchlight, 0.87f, 0.06f),
                     NormalizedDiffusion::from_length(kSearchlight, 0.85f, 0.05f),
                     NormalizedDiffusion::from_length(kSearchlight, 0.82f, 0.045f)});
}

RgbProfile jade() {
  return RgbProfile({NormalizedDiffusion::from_length(kSearchlight, 0.4f, 0.12f),
                     NormalizedDiffusion::from_length(kSearchlight, 0.8f, 0.3f),
                     NormalizedDiffusion::from_length(kSearchlight, 0.52f, 0.16f)});
}

// One call per iteration reported as a counter too: CPU seconds per call (shown as ns).
void set_per_call(benchmark::State& state) {
  state.SetItemsProcessed(state.iterations());
  state.counters["ns_per_call"] =
      benchmark::Counter(1.0, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

// This thread's CPU time in ns (leaves out the time the thread sits preempted on a shared machine).
double thread_cpu_ns() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e9 + static_cast<double>(ts.tv_nsec);
}

// ---- profile evaluation -----------------------------------------------------------------------------

// Radii from the profile's own radius sampling, stratified in u and shuffled so the branch on r and
// the exp arguments do not follow a predictable ramp. channel < 0: a random channel per radius.
std::vector<float> make_radii(const RgbProfile& p, int channel) {
  std::vector<float> r(kInputs);
  Pcg32 rng(0x6b6f7a75u, 11);
  for (size_t i = 0; i < kInputs; ++i) {
    const float u = (static_cast<float>(i) + rng.next_float()) / static_cast<float>(kInputs);
    const int c = channel >= 0 ? channel : static_cast<int>(rng.next_u32() % 3);
    r[i] = p.sample_radius(c, u);
  }
  for (size_t i = kInputs - 1; i > 0; --i) std::swap(r[i], r[rng.next_u32() % (i + 1)]);
  return r;
}

void BM_ProfileEval(benchmark::State& state) {
  const RgbProfile profile = marble();
  const bool rgb = state.range(0) == 1;
  const std::vector<float> radii = make_radii(profile, rgb ? -1 : 0);
  const NormalizedDiffusion ch = profile.channel(0);
  size_t i = 0;
  if (rgb) {
    for (auto _ : state) {
      Rgb v = profile.eval(radii[i++ & kMask]);
      benchmark::DoNotOptimize(v);
    }
  } else {
    for (auto _ : state) {
      float v = ch.eval(radii[i++ & kMask]);
      benchmark::DoNotOptimize(v);
    }
  }
  set_per_call(state);
  state.SetLabel(rgb ? "RgbProfile::eval (3 channels)" : "NormalizedDiffusion::eval");
}
BENCHMARK(BM_ProfileEval)->Arg(0)->Arg(1)->ArgName("rgb");

// ---- radius sampling --------------------------------------------------------------------------------

const std::vector<float>& u_table() {
  static const std::vector<float> u = [] {
    std::vector<float> v(kInputs);
    Pcg32 rng(0x6b6f7a75u, 12);
    for (float& x : v) x = rng.next_float();
    return v;
  }();
  return u;
}

void BM_RadiusSample_ClosedForm(benchmark::State& state) {
  const NormalizedDiffusion ch = marble().channel(0);
  const std::vector<float>& u = u_table();
  size_t i = 0;
  for (auto _ : state) {
    float r = ch.sample_closed_form(u[i++ & kMask]);
    benchmark::DoNotOptimize(r);
  }
  set_per_call(state);
}
BENCHMARK(BM_RadiusSample_ClosedForm);

void BM_RadiusSample_Newton(benchmark::State& state) {
  const NormalizedDiffusion ch = marble().channel(0);
  const std::vector<float>& u = u_table();
  size_t i = 0;
  for (auto _ : state) {
    float r = ch.sample(u[i++ & kMask]);
    benchmark::DoNotOptimize(r);
  }
  set_per_call(state);
  // Iterations over the same table, counted outside the timed loop.
  double sum = 0.0;
  int most = 0;
  for (const float x : u) {
    int k = 0;
    ch.sample(x, &k);
    sum += k;
    most = std::max(most, k);
  }
  state.counters["mean_iterations"] = sum / static_cast<double>(u.size());
  state.counters["max_iterations"] = most;
}
BENCHMARK(BM_RadiusSample_Newton);

// The two methods on the same u in interleaved blocks, each block timed by thread CPU time.
void BM_RadiusSample_NewtonVsClosed(benchmark::State& state) {
  constexpr size_t kBlock = 1024;  // the clock reads stay well under 1% of a block
  const NormalizedDiffusion ch = marble().channel(0);
  const std::vector<float>& u = u_table();
  double t_closed = 0.0, t_newton = 0.0;
  size_t i = 0;
  bool closed_first = true;
  auto run_closed = [&] {
    for (size_t k = 0; k < kBlock; ++k) {
      float r = ch.sample_closed_form(u[(i + k) & kMask]);
      benchmark::DoNotOptimize(r);
    }
  };
  auto run_newton = [&] {
    for (size_t k = 0; k < kBlock; ++k) {
      float r = ch.sample(u[(i + k) & kMask]);
      benchmark::DoNotOptimize(r);
    }
  };
  for (auto _ : state) {
    const double t0 = thread_cpu_ns();
    closed_first ? run_closed() : run_newton();
    const double t1 = thread_cpu_ns();
    closed_first ? run_newton() : run_closed();
    const double t2 = thread_cpu_ns();
    (closed_first ? t_closed : t_newton) += t1 - t0;
    (closed_first ? t_newton : t_closed) += t2 - t1;
    closed_first = !closed_first;
    i += kBlock;
  }
  const double calls = static_cast<double>(state.iterations()) * kBlock;
  state.counters["closed_ns"] = calls > 0 ? t_closed / calls : 0.0;
  state.counters["newton_ns"] = calls > 0 ? t_newton / calls : 0.0;
  state.counters["newton/closed"] = t_closed > 0 ? t_newton / t_closed : 0.0;
  state.SetItemsProcessed(static_cast<int64_t>(2 * calls));
}
BENCHMARK(BM_RadiusSample_NewtonVsClosed);

// Agreement of the two inversions and each one's residual in the CDF (no timing).
void BM_RadiusSample_Agreement(benchmark::State& state) {
  constexpr int kN = 1000000;
  const NormalizedDiffusion ch = marble().channel(0);
  const double d = ch.d();
  double max_rel = 0.0, max_cdf_closed = 0.0, max_cdf_newton = 0.0;
  int64_t differ = 0;
  auto check = [&](float u) {
    const float rc = ch.sample_closed_form(u), rn = ch.sample(u);
    max_rel = std::max(max_rel, std::abs(static_cast<double>(rc) - rn) / std::max(static_cast<double>(rc), d));
    max_cdf_closed = std::max(max_cdf_closed, std::abs(ch.cdf(rc) - u));
    max_cdf_newton = std::max(max_cdf_newton, std::abs(ch.cdf(rn) - u));
    differ += rc != rn;
  };
  for (auto _ : state) {
    for (int k = 0; k < kN; ++k) check(static_cast<float>((k + 0.5) / kN));
    // The two ends, which the stratified set only touches: u down to 2^-40 (r → 0) and the floats
    // just below 1 (the far tail, r up to ~50 d).
    for (int k = 0; k <= 4000; ++k) check(std::exp2(-0.01f * static_cast<float>(k)) * 0.999f);
    for (int k = 1; k <= 4096; ++k) check(1.0f - static_cast<float>(k) * 0x1p-24f);
  }
  state.counters["max_rel_diff"] = max_rel;
  state.counters["n_differ"] = static_cast<double>(differ);
  state.counters["max_cdf_err_closed"] = max_cdf_closed;
  state.counters["max_cdf_err_newton"] = max_cdf_newton;
}
BENCHMARK(BM_RadiusSample_Agreement)->Iterations(1)->Unit(benchmark::kMillisecond);

// ---- probe sampling ---------------------------------------------------------------------------------

struct ProbeFixture {
  std::vector<std::unique_ptr<Shape>> shapes;
  std::unique_ptr<EmbreeScene> scene;
  std::vector<SurfaceInteraction> entries;
};

// The shape alone in an Embree scene, and kEntries points where rays from a sphere around it, aimed at
// random points of its bounding box, first hit it.
std::unique_ptr<ProbeFixture> make_probe_fixture(std::unique_ptr<Shape> shape) {
  auto f = std::make_unique<ProbeFixture>();
  f->shapes.push_back(std::move(shape));
  f->scene = std::make_unique<EmbreeScene>(f->shapes);
  Vec3 lo(kInfinity), hi(-kInfinity);  // bounds() grows the box it is given
  f->shapes[0]->bounds(lo, hi);
  const Vec3 centre = 0.5f * (lo + hi);
  const float radius = glm::length(hi - lo);
  Pcg32 rng(0x6b6f7a75u, 13);
  for (int tries = 0; f->entries.size() < kEntries && tries < 100000; ++tries) {
    const float a = rng.next_float();
    const Vec3 o = centre + radius * warp::square_to_uniform_sphere(Vec2(a, rng.next_float()));
    const float x = rng.next_float(), y = rng.next_float(), z = rng.next_float();
    const Vec3 target = lo + Vec3(x, y, z) * (hi - lo);
    SurfaceInteraction si;
    if (f->scene->intersect(Ray{o, glm::normalize(target - o), kInfinity}, si)) f->entries.push_back(si);
  }
  return f;
}

const ProbeFixture& probe_fixture(int shape) {
  static std::map<int, std::unique_ptr<ProbeFixture>> cache;
  auto& f = cache[shape];
  if (!f) {
    if (shape == 0) {
      f = make_probe_fixture(std::make_unique<Sphere>(Vec3(0.0f), 0.6f));
    } else {
      MeshData m = load_mesh(std::string(KOZU_SOURCE_DIR) + "/scenes/meshes/torus.ply");
      f = make_probe_fixture(std::make_unique<TriangleMesh>(std::move(m.positions), std::move(m.indices),
                                                            std::move(m.normals), std::move(m.uvs)));
    }
  }
  return *f;
}

const std::vector<Vec4>& probe_u() {
  static const std::vector<Vec4> u = [] {
    std::vector<Vec4> v(kInputs);
    Pcg32 rng(0x6b6f7a75u, 14);
    for (Vec4& x : v) {
      const float a = rng.next_float(), b = rng.next_float(), c = rng.next_float();
      x = Vec4(a, b, c, rng.next_float());
    }
    return v;
  }();
  return u;
}

// range(0): 0 sphere (r = 0.6), 1 torus (scenes/meshes/torus.ply); range(1): 0 marble, 1 jade.
void BM_ProbeSample(benchmark::State& state) {
  const ProbeFixture& f = probe_fixture(static_cast<int>(state.range(0)));
  const RgbProfile profile = state.range(1) == 0 ? marble() : jade();
  const std::vector<Vec4>& u = probe_u();
  if (f.entries.size() < kEntries) {
    state.SkipWithError("too few entry points found");
    return;
  }
  uint64_t rays = 0, hits = 0;
  size_t i = 0;
  for (auto _ : state) {
    ProbeSample ps;
    const bool ok = sample_probe(*f.scene, f.entries[(i * 17) % kEntries], profile, u[i & kMask], &ps, &rays);
    benchmark::DoNotOptimize(ps);
    hits += ok;
    ++i;
  }
  set_per_call(state);
  const double n = static_cast<double>(state.iterations());
  state.counters["probe_rays"] = n > 0 ? static_cast<double>(rays) / n : 0.0;
  state.counters["hit_fraction"] = n > 0 ? static_cast<double>(hits) / n : 0.0;
  state.SetLabel(std::string(state.range(0) == 0 ? "sphere r=0.6" : "torus.ply") + ", " +
                 (state.range(1) == 0 ? "marble" : "jade"));
}
BENCHMARK(BM_ProbeSample)->Args({0, 0})->Args({1, 0})->Args({1, 1})->ArgNames({"shape", "profile"});

// ---- showcase scene ---------------------------------------------------------------------------------

constexpr int kWidth = 320;
constexpr int kHeight = 180;
constexpr int kSppPerIteration = 4;
constexpr int kThreads = 2;

const char* showcase_name(int64_t i) { return i == 0 ? "subsurface" : "subsurface_lambert"; }

const Scene& showcase(int64_t i) {
  static std::map<int64_t, std::unique_ptr<Scene>> cache;
  static std::mutex mutex;
  std::lock_guard lock(mutex);
  auto& s = cache[i];
  if (!s) {
    s = load_scene_file(std::string(KOZU_SOURCE_DIR) + "/scenes/" + showcase_name(i) + ".json");
    s->camera.set_resolution(Vec2i(kWidth, kHeight));
  }
  return *s;
}

RenderResult render_showcase(const Scene& scene, const PathIntegrator& integrator) {
  RenderSettings opt;
  opt.spp = kSppPerIteration;
  opt.threads = kThreads;
  opt.seed = scene.settings.seed;
  Film film(kWidth, kHeight);
  return render(scene, integrator, film, opt);
}

void BM_ShowcaseScene(benchmark::State& state) {
  const Scene& scene = showcase(state.range(0));
  PathIntegrator integrator(scene, scene.settings.max_depth);
  double seconds = 0, paths = 0, rays = 0;
  for (auto _ : state) {
    const RenderResult r = render_showcase(scene, integrator);
    state.SetIterationTime(r.seconds);
    seconds += r.seconds;
    paths += static_cast<double>(r.paths);
    rays += static_cast<double>(r.rays.total());
  }
  state.counters["samples_per_s"] = seconds > 0 ? paths / seconds : 0.0;
  state.counters["rays_per_s"] = seconds > 0 ? rays / seconds : 0.0;
  state.counters["rays_per_sample"] = paths > 0 ? rays / paths : 0.0;
  state.SetLabel(showcase_name(state.range(0)));
}
BENCHMARK(BM_ShowcaseScene)
    ->Arg(0)
    ->Arg(1)
    ->ArgName("scene")
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

// Subsurface and Lambert alternately in one loop; one iteration renders both, in alternating order.
void BM_ShowcaseCostRatio(benchmark::State& state) {
  const Scene& sss = showcase(0);
  const Scene& lam = showcase(1);
  PathIntegrator sss_integrator(sss, sss.settings.max_depth);
  PathIntegrator lam_integrator(lam, lam.settings.max_depth);
  double t[2] = {0, 0}, paths[2] = {0, 0}, rays[2] = {0, 0}, probe[2] = {0, 0};
  auto run = [&](int k) {
    const RenderResult r = k == 0 ? render_showcase(sss, sss_integrator) : render_showcase(lam, lam_integrator);
    t[k] += r.seconds;
    paths[k] += static_cast<double>(r.paths);
    rays[k] += static_cast<double>(r.rays.total());
    probe[k] += static_cast<double>(r.rays.probe_rays);
    return r.seconds;
  };
  bool sss_first = true;
  for (auto _ : state) {
    const double a = run(sss_first ? 0 : 1);
    const double b = run(sss_first ? 1 : 0);
    state.SetIterationTime(a + b);
    sss_first = !sss_first;
  }
  if (paths[0] > 0 && paths[1] > 0 && t[1] > 0) {
    state.counters["cost_ratio"] = (t[0] / paths[0]) / (t[1] / paths[1]);
    state.counters["sss_samples_per_s"] = paths[0] / t[0];
    state.counters["lambert_samples_per_s"] = paths[1] / t[1];
    state.counters["sss_rays_per_sample"] = rays[0] / paths[0];
    state.counters["lambert_rays_per_sample"] = rays[1] / paths[1];
    state.counters["sss_probe_rays_per_sample"] = probe[0] / paths[0];
  }
}
BENCHMARK(BM_ShowcaseCostRatio)->UseManualTime()->Unit(benchmark::kMillisecond)->MinTime(4.0);

}  // namespace
}  // namespace kozu

BENCHMARK_MAIN();
