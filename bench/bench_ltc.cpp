// Linearly transformed cosines (lights/ltc.h), in ns per call: the polygon integral of eqs. (3) and (11) for 3, 4
// and 8 corners (transform, horizon clip, edge terms in double), eval and sample.
//
//   build/bench/bench_ltc --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include "core/ltc.h"
#include "core/rng.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

namespace kozu {
namespace {

// A glossy lobe's LTC of the fitted form (seed eq. 6) and 256 polygons of n corners around the shading point's
// upper hemisphere, a quarter of them crossing the horizon.
struct Setup {
  Ltc ltc;
  std::vector<std::vector<Vec3>> polygons;
  std::vector<Vec2> u;
  explicit Setup(int n) {
    Mat3 m(1.0f);
    m[0][0] = 0.3f;  // glm is column-major: m[column][row]
    m[2][0] = 0.2f;
    m[1][1] = 0.3f;
    m[0][2] = -0.1f;
    ltc = Ltc(m);
    Pcg32 rng(5);
    for (int k = 0; k < 256; ++k) {
      const Vec3 c(2.0f * rng.next_float() - 1.0f, 2.0f * rng.next_float() - 1.0f, 1.2f - 0.8f * rng.next_float());
      std::vector<Vec3> p;
      for (int i = 0; i < n; ++i) {
        const float phi = kTwoPi * static_cast<float>(i) / static_cast<float>(n);
        p.push_back(c + 0.5f * Vec3(std::cos(phi), std::sin(phi), 0.2f * std::sin(phi)));
      }
      polygons.push_back(p);
      u.emplace_back(rng.next_float(), rng.next_float());
    }
  }
};

void BM_LtcPolygonIntegral(benchmark::State& state) {
  const Setup s(static_cast<int>(state.range(0)));
  size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(s.ltc.integrate_polygon(s.polygons[i++ & 255]));
}
BENCHMARK(BM_LtcPolygonIntegral)->Arg(3)->Arg(4)->Arg(8);

void BM_LtcEval(benchmark::State& state) {
  const Setup s(4);
  size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(s.ltc.eval(glm::normalize(s.polygons[i++ & 255][0])));
}
BENCHMARK(BM_LtcEval);

void BM_LtcSample(benchmark::State& state) {
  const Setup s(4);
  size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(s.ltc.sample(s.u[i++ & 255]));
}
BENCHMARK(BM_LtcSample);

}  // namespace
}  // namespace kozu

BENCHMARK_MAIN();
