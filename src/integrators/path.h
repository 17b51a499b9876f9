// Unidirectional path tracing with next-event estimation.
//
// At every non-delta vertex one light is chosen in proportion to its power and sampled; the
// result is combined with BSDF sampling by multiple importance sampling with the power
// heuristic (Veach 1997, ch. 9). Emission found by BSDF-sampled rays carries the matching MIS
// weight; emission seen directly by the camera or through delta lobes carries weight 1.
// Russian roulette starts after three bounces with survival probability min(1, max(beta * eta^2))
// (the eta^2 factor removes the radiance scaling of refraction from the decision).
// Light leaks through shading normals are prevented by requiring the geometric and shading
// normals to agree on whether a direction pair is reflection or transmission (Veach 1996).
//
// BSSRDFs (Material::subsurface_profile): at a subsurface boundary a transmitted BSDF sample is not
// followed; probe rays (bssrdf/probe_sampling.h) pick the point where the light leaves, weighted by
// R(r) / pdf, and the path goes on from there as a second vertex with the material's exit BSDF
// (NEE and BSDF sampling as at any vertex). Probe queries are counted as probe_rays.
//
// Seams for later work: participating media (a medium-aware integrator beside this one), analytic
// polygon-light integration (PolygonLight keeps polygons whole).
#pragma once

#include "integrators/integrator.h"
#include "scene/scene.h"

namespace kozu {

class PathIntegrator final : public Integrator {
 public:
  PathIntegrator(const Scene& scene, int max_depth) : scene_(scene), max_depth_(max_depth) {}
  Rgb li(const Ray& ray, Sampler& sampler, Arena& arena, RayCounters& counters, const StopFlag& stop) const override;

 private:
  // Transmittance along a shadow ray that starts in `medium`, through index-matched boundaries.
  Rgb transmittance(Ray ray, const Medium* medium, Pcg32& rng, RayCounters& counters, PathBudget& budget) const;

  const Scene& scene_;
  int max_depth_;
};

}  // namespace kozu
