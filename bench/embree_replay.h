// Replaying recorded rays (RayLog) through Embree alone, for bench_render and bench_rays: one closest-hit or
// occlusion query per ray, nothing else.
#pragma once

#include "geometry/ray.h"

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

}  // namespace kozu::bench
