// Ray cones: the footprint a path's rays carry from the camera through every bounce, for texture filtering.
//
// Citations: Akenine-Möller, Nilsson, Andersson, Barré-Brisebois, Toth, Karras 2019, "Texture Level of Detail
// Strategies for Real-Time Ray Tracing" (Ray Tracing Gems ch. 20, §20.3.4): a cone of width w and spread angle γ
// grows as w(t) = w + γ t, and a bounce adds the surface spread angle β (γ' = γ + β), twice the normal's turn
// across the footprint at a curved mirror; Akenine-Möller,
// Crassin, Boksansky, Belcour, Panteleev, Wright 2021, "Improved Shader and Texture Level of Detail Using Ray
// Cones" (JCGT 10(1)), for curvature from vertex normals and refraction; Suykens & Willems 2001, "Path
// Differentials and Applications" (EGWR), for a sampled (rough) bounce: of N paths through a pixel, one that
// drew its direction with density p stands for the solid angle 1/(N p) of the lobe.
//
// kozu's forms (γ is the full angle; negative: the cone converges; κ the surface's curvature seen from the side
// the ray arrives on, > 0 convex, 1/r on a sphere seen from outside):
//   mirror reflection       γ' = γ + 2 κ w                       (the normal turns by κ w across the footprint)
//   smooth refraction       γ' = γ / η − (1 − 1/η) κ w           (paraxial Snell: angles scale by 1/η, and the
//                                                                 turned normal bends the edges by (1 − 1/η) κ w;
//                                                                 η = IOR on the far side / IOR on this side)
//   rough (sampled) bounce  γ' = |γ| + γ_lobe(N p),  γ_lobe(q) = 2 acos(1 − 1/(2π q)), at most π
//                           (the cone of solid angle 2π (1 − cos(γ_lobe/2)) = 1/(N p), N the pixel's samples;
//                           curvature is left out: it is the footprint's own width times κ, small against any
//                           lobe's). With N in it the filtering vanishes as N grows, so the blur it adds to a
//                           rough reflection (the lobe convolved with the footprint) vanishes too: the image
//                           converges to the unfiltered one.
// The forms are exact at normal incidence in the paraxial limit (tests/geometry/test_ray_cone.cpp traces the
// edge rays); at oblique incidence a round cone cannot carry the astigmatism a curved surface gives, as in the
// papers.
#pragma once

#include "core/math.h"

#include <algorithm>
#include <cmath>

namespace kozu {

struct RayCone {
  float width = 0;   // at the ray's origin
  float spread = 0;  // full angle, radians

  // The cone's width where the ray has gone t (its absolute value: a converging cone passes a focus).
  float width_at(float t) const { return std::abs(width + spread * t); }

  // The first t > t0 where the width leaves [lo, hi) (a crossing of ±lo or ±hi by width + spread t), or infinity:
  // where a level of detail chosen at t0 stops serving the cone (Medium::level_for).
  float leaves(float t0, float lo, float hi) const {
    if (spread == 0.0f) return kInfinity;
    float t = kInfinity;
    for (const float c : {lo, -lo, hi, -hi}) {
      const float tc = (c - width) / spread;
      if (tc > t0 && tc < t && (c != 0.0f)) t = tc;  // lo = 0: a focus (width 0) stays in range
    }
    return t;
  }

  // The cone leaving a hit where it had width w, after a mirror reflection on a surface of curvature kappa.
  RayCone reflected(float w, float kappa) const { return {w, spread + 2.0f * kappa * w}; }
  // ... after a smooth refraction with relative IOR eta.
  RayCone refracted(float w, float kappa, float eta) const {
    const float inv = 1.0f / eta;
    return {w, spread * inv - (1.0f - inv) * kappa * w};
  }
  // ... after a direction sampled with solid-angle density pdf (a rough lobe or a phase function) by one of
  // paths paths through the pixel.
  RayCone scattered(float w, float pdf, float paths = 1.0f) const {
    return {w, std::abs(spread) + lobe_spread(pdf * paths)};
  }

  // The full angle of the cone whose solid angle is 1/density, at most π (a hemisphere).
  static float lobe_spread(float density) {
    if (!(density > 0.0f)) return kPi;
    // 2 acos(c) by Abramowitz & Stegun 4.4.45: acos c = sqrt(1 − c) P(c), |error| ≤ 5e-5 rad (relative 5e-5 as
    // c → 1). A footprint needs no more, std::acos cost 3 % of a render, and 1 − c known exactly keeps narrow lobes'
    // angles precise where c rounds to 1.
    const float one_minus_c = 1.0f / (2.0f * kPi * density);
    if (one_minus_c >= 1.0f) return kPi;
    const float c = 1.0f - one_minus_c;
    const float acos_c = std::sqrt(one_minus_c) * (1.5707288f + c * (-0.2121144f + c * (0.0742610f + c * -0.0187293f)));
    return std::min(kPi, 2.0f * acos_c);
  }
};

}  // namespace kozu
