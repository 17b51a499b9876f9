// What bench_render and bench_rays share: renders timed per benchmark iteration, and recorded rays (RayLog)
// replayed through Embree alone, one closest-hit or occlusion query per ray, nothing else.
#pragma once

#include "geometry/ray.h"
#include "integrators/path.h"
#include "render/renderer.h"

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>

namespace kozu::bench {

inline RTCRayHit ray_hit(const Ray& ray) {
  RTCRayHit rh;
  rh.ray.org_x = ray.o.x, rh.ray.org_y = ray.o.y, rh.ray.org_z = ray.o.z;
  rh.ray.dir_x = ray.d.x, rh.ray.dir_y = ray.d.y, rh.ray.dir_z = ray.d.z;
  rh.ray.tnear = 0.0f, rh.ray.tfar = ray.tmax, rh.ray.time = 0.0f;
  rh.ray.mask = 0xffffffffu, rh.ray.id = 0, rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return rh;
}

inline void trace_closest(RTCScene s, const Ray& ray,
                          RTCIntersectContextFlags flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = flags;
  RTCRayHit rh = ray_hit(ray);
  rtcIntersect1(s, &ctx, &rh);
  benchmark::DoNotOptimize(rh.hit.geomID);
}

inline void trace_shadow(RTCScene s, const Ray& ray) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay r = ray_hit(ray).ray;
  rtcOccluded1(s, &ctx, &r);
  benchmark::DoNotOptimize(r.tfar);
}

// Renders spp samples per pixel of the scene on `threads` threads per iteration; reports samples/s and rays/s over
// all iterations (every ray the renders traced) and returns the rays/s.
inline double measure_renders(benchmark::State& state, const Scene& scene, int threads, int spp, Vec2i resolution) {
  PathIntegrator integrator(scene, scene.settings.max_depth);
  RenderSettings opt;
  opt.spp = spp;
  opt.threads = threads;
  double seconds = 0, paths = 0, rays = 0;
  for (auto _ : state) {
    Film film(resolution.x, resolution.y);
    const RenderResult r = render(scene, integrator, film, opt);
    state.SetIterationTime(r.seconds);
    seconds += r.seconds;
    paths += static_cast<double>(r.paths);
    rays += static_cast<double>(r.rays.total());
  }
  state.counters["samples_per_s"] = paths / seconds;
  state.counters["rays_per_s"] = rays / seconds;
  return rays / seconds;
}

}  // namespace kozu::bench
