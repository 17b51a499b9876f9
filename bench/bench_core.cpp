// Costs of the renderer's building blocks, in ns per call: sampler dimensions, warps, BSDF
// eval/sample/pdf, light sampling and single-ray Embree queries.
//
//   build/bench/bench_core --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include "core/rng.h"
#include "core/sampler.h"
#include "core/warp.h"
#include "lights/environment.h"
#include "materials/dielectric.h"
#include "materials/diffuse.h"
#include "scene/scene_loader.h"

#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <vector>

namespace kozu {
namespace {

// Pre-drawn uniforms so that the RNG is not part of what is measured.
const std::vector<Vec2>& uniforms() {
  static const std::vector<Vec2> u = [] {
    std::vector<Vec2> v(4096);
    Pcg32 rng(1);
    for (auto& x : v) x = Vec2(rng.next_float(), rng.next_float());
    return v;
  }();
  return u;
}

void BM_SamplerNext1D(benchmark::State& state) {
  Sampler s(1);
  uint32_t i = 0;
  for (auto _ : state) {
    if ((i & 15) == 0) s.start(i & 511, i >> 9, i >> 4);
    benchmark::DoNotOptimize(s.next_1d());
    ++i;
  }
}
BENCHMARK(BM_SamplerNext1D);

void BM_SamplerNext2D(benchmark::State& state) {
  Sampler s(1);
  uint32_t i = 0;
  for (auto _ : state) {
    if ((i & 15) == 0) s.start(i & 511, i >> 9, i >> 4);
    benchmark::DoNotOptimize(s.next_2d());
    ++i;
  }
}
BENCHMARK(BM_SamplerNext2D);

void BM_SamplerNext4D(benchmark::State& state) {
  Sampler s(1);
  uint32_t i = 0;
  for (auto _ : state) {
    if ((i & 15) == 0) s.start(i & 511, i >> 9, i >> 4);
    benchmark::DoNotOptimize(s.next_4d());
    ++i;
  }
}
BENCHMARK(BM_SamplerNext4D);

// The scalar form next_4d's SIMD lanes replace (the same numbers), for the ratio in one run.
void BM_SamplerNext4DPortable(benchmark::State& state) {
  Sampler s(1);
  uint32_t i = 0;
  for (auto _ : state) {
    if ((i & 15) == 0) s.start(i & 511, i >> 9, i >> 4);
    benchmark::DoNotOptimize(s.next_4d_portable());
    ++i;
  }
}
BENCHMARK(BM_SamplerNext4DPortable);

void BM_Pcg32Float(benchmark::State& state) {
  Pcg32 rng(1);
  for (auto _ : state) benchmark::DoNotOptimize(rng.next_float());
}
BENCHMARK(BM_Pcg32Float);

void BM_CosineHemisphere(benchmark::State& state) {
  const auto& u = uniforms();
  size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(warp::square_to_cosine_hemisphere(u[i++ & 4095]));
}
BENCHMARK(BM_CosineHemisphere);

void BM_DiffuseSample(benchmark::State& state) {
  const DiffuseBsdf bsdf(Rgb(0.5f));
  const Vec3 wo = glm::normalize(Vec3(0.3f, 0.2f, 0.9f));
  const auto& u = uniforms();
  size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(bsdf.sample(wo, 0.5f, u[i++ & 4095], TransportMode::Radiance));
}
BENCHMARK(BM_DiffuseSample);

void BM_DiffuseEval(benchmark::State& state) {
  const DiffuseBsdf bsdf(Rgb(0.5f));
  const Vec3 wo = glm::normalize(Vec3(0.3f, 0.2f, 0.9f));
  const auto& u = uniforms();
  size_t i = 0;
  for (auto _ : state)
    benchmark::DoNotOptimize(bsdf.eval(wo, warp::square_to_cosine_hemisphere(u[i++ & 4095]), TransportMode::Radiance));
}
BENCHMARK(BM_DiffuseEval);

void BM_DielectricSample(benchmark::State& state) {
  const SmoothDielectricBsdf bsdf(1.5f);
  const Vec3 wo = glm::normalize(Vec3(0.3f, 0.2f, 0.9f));
  const auto& u = uniforms();
  size_t i = 0;
  for (auto _ : state) {
    const Vec2 x = u[i++ & 4095];
    benchmark::DoNotOptimize(bsdf.sample(wo, x.x, x, TransportMode::Radiance));
  }
}
BENCHMARK(BM_DielectricSample);

// Light sampling from points on the Cornell floor: selection plus the chosen light's sample.
void BM_CornellLightSample(benchmark::State& state) {
  static auto scene = load_scene_file(std::string(KOZU_SOURCE_DIR) + "/scenes/cornell.json");
  const auto& u = uniforms();
  size_t i = 0;
  for (auto _ : state) {
    const Vec2 x = u[i++ & 4095];
    const LightSampleContext ctx{Vec3(100.0f + 300.0f * x.x, 0.0f, 100.0f + 300.0f * x.y), Vec3(0, 1, 0)};
    float pmf, ur;
    const Light* l = scene->light_sampler().sample(x.y, &pmf, &ur);
    benchmark::DoNotOptimize(l->sample(ctx, Vec2(ur, x.x)));
  }
}
BENCHMARK(BM_CornellLightSample);

// One closest-hit query plus hit reconstruction, random rays from the Cornell camera.
void BM_CornellIntersect(benchmark::State& state) {
  static auto scene = load_scene_file(std::string(KOZU_SOURCE_DIR) + "/scenes/cornell.json");
  const auto& u = uniforms();
  size_t i = 0;
  for (auto _ : state) {
    const Vec2 x = u[i++ & 4095];
    const Ray r = scene->camera.generate_ray(Vec2(512.0f * x.x, 512.0f * x.y), Vec2(0.5f));
    SurfaceInteraction si;
    benchmark::DoNotOptimize(scene->intersect(r, si));
  }
}
BENCHMARK(BM_CornellIntersect);

// A studio HDRI of state.range(0) x range(0)/2 pixels: a dim gradient, two bright softboxes and a little noise, as
// the product shot of bench/cycles lights. Sampling it and evaluating it (radiance and density, as a BSDF ray that
// escapes does) at directions spread over the sphere, so that the lookups miss the caches as a render's do.
std::vector<Rgb> studio_pixels(int width, int height) {
  std::vector<Rgb> px(static_cast<size_t>(width) * height);
  Pcg32 rng(7);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const float u = (x + 0.5f) / width, v = (y + 0.5f) / height;
      float L = 0.05f + 0.2f * (1.0f - v) + 0.02f * rng.next_float();
      const auto box = [&](float cu, float cv, float hu, float hv) { return std::abs(u - cu) < hu && std::abs(v - cv) < hv; };
      if (box(0.3f, 0.3f, 0.04f, 0.06f) || box(0.7f, 0.35f, 0.05f, 0.05f)) L = 40.0f;
      px[static_cast<size_t>(y) * width + x] = Rgb(L, 0.95f * L, 0.9f * L);
    }
  return px;
}

const EnvironmentLight& studio(int width) {
  static std::map<int, std::unique_ptr<EnvironmentLight>> lights;
  if (auto it = lights.find(width); it != lights.end()) return *it->second;
  const int height = width / 2;
  auto light = std::make_unique<EnvironmentLight>(studio_pixels(width, height), width, height, 1.0f, 0.0f);
  light->preprocess(Vec3(0.0f), 1.0f);
  return *(lights[width] = std::move(light));
}

// std::atan2 against fast_atan2 (core/math.h) on directions around the circle, each call independent.
template <bool kFast>
void BM_Atan2(benchmark::State& state) {
  std::vector<Vec2> xy(4096);
  Pcg32 rng(5);
  for (auto& p : xy) {
    const float a = kTwoPi * rng.next_float();
    p = Vec2(std::cos(a), std::sin(a));
  }
  size_t i = 0;
  for (auto _ : state) {
    const Vec2& p = xy[i++ & 4095];
    benchmark::DoNotOptimize(kFast ? fast_atan2(p.y, p.x) : std::atan2(p.y, p.x));
  }
}
BENCHMARK(BM_Atan2<false>)->Name("BM_Atan2/std");
BENCHMARK(BM_Atan2<true>)->Name("BM_Atan2/fast");

// 64 Ki pre-drawn uniforms: more than any cache holds of the lookups they lead to.
const std::vector<Vec2>& many_uniforms() {
  static const std::vector<Vec2> u = [] {
    std::vector<Vec2> v(1 << 16);
    Pcg32 rng(3);
    for (auto& x : v) x = Vec2(rng.next_float(), rng.next_float());
    return v;
  }();
  return u;
}

void BM_EnvironmentSample(benchmark::State& state) {
  const EnvironmentLight& env = studio(static_cast<int>(state.range(0)));
  const auto& u = many_uniforms();
  const LightSampleContext ctx{Vec3(0.0f), Vec3(0.0f)};
  size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(env.sample(ctx, u[i++ & 0xffff]));
}
BENCHMARK(BM_EnvironmentSample)->Arg(512)->Arg(2048);

void BM_EnvironmentEvalPdf(benchmark::State& state) {
  const EnvironmentLight& env = studio(static_cast<int>(state.range(0)));
  const auto& u = many_uniforms();
  const LightSampleContext ctx{Vec3(0.0f), Vec3(0.0f)};
  size_t i = 0;
  for (auto _ : state) {
    const LightHit hit{warp::square_to_uniform_sphere(u[i++ & 0xffff])};
    float pdf;
    benchmark::DoNotOptimize(env.eval_pdf(ctx, hit, &pdf));
    benchmark::DoNotOptimize(pdf);
  }
}
BENCHMARK(BM_EnvironmentEvalPdf)->Arg(512)->Arg(2048);

// The same map seen through a window (lights/environment_portal.h): bench/cycles' interior, a 1.6 x 1.2 m window in
// the wall x = 3 of a 6 x 3 x 5 m room, sampled and evaluated from points spread through the room.
const EnvironmentLight& studio_through_window() {
  static const std::unique_ptr<EnvironmentLight> light = [] {
    // Turned so that a softbox shows through the window.
    auto env = std::make_unique<EnvironmentLight>(studio_pixels(512, 256), 512, 256, 1.0f, 90.0f);
    env->preprocess(Vec3(0.0f), 1.0f);
    env->set_portals({{Vec3(3, 0.9f, -0.8f), Vec3(3, 0.9f, 0.8f), Vec3(3, 2.1f, 0.8f), Vec3(3, 2.1f, -0.8f)}});
    return env;
  }();
  return *light;
}

const std::vector<Vec3>& room_points() {
  static const std::vector<Vec3> p = [] {
    std::vector<Vec3> v(4096);
    Pcg32 rng(9);
    for (auto& x : v) x = Vec3(-3.0f + 5.9f * rng.next_float(), 3.0f * rng.next_float(), -2.5f + 5.0f * rng.next_float());
    return v;
  }();
  return p;
}

// A light sample, or the radiance and density of a BSDF ray that escapes, from points through the room.
template <bool kEvalPdf>
void BM_EnvironmentPortal(benchmark::State& state) {
  const EnvironmentLight& env = studio_through_window();
  const auto& u = many_uniforms();
  const auto& p = room_points();
  size_t i = 0;
  for (auto _ : state) {
    const LightSampleContext ctx{p[i & 4095], Vec3(0.0f)};
    const Vec2& ui = u[i++ & 0xffff];
    if constexpr (kEvalPdf) {
      float pdf;
      benchmark::DoNotOptimize(env.eval_pdf(ctx, LightHit{warp::square_to_uniform_sphere(ui)}, &pdf));
      benchmark::DoNotOptimize(pdf);
    } else {
      benchmark::DoNotOptimize(env.sample(ctx, ui));
    }
  }
}
BENCHMARK(BM_EnvironmentPortal<false>)->Name("BM_EnvironmentPortalSample");
BENCHMARK(BM_EnvironmentPortal<true>)->Name("BM_EnvironmentPortalEvalPdf");

}  // namespace
}  // namespace kozu

BENCHMARK_MAIN();
