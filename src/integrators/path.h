// Unidirectional path tracing with next-event estimation, through surfaces, BSSRDFs and media.
//
// A path is a chain of vertices of two kinds, each doing the same three things (path.cpp):
//  - a surface vertex (a BSDF at a ray hit) and a medium vertex (a phase function where free-flight
//    sampling, media/tracking.h, stops the ray inside a medium);
//  - each samples one light (direct_lighting: light choice in proportion to power, shadow transmittance
//    through index-matched medium boundaries, MIS with the power heuristic, Veach 1997 ch. 9), samples its
//    own lobe to continue, and plays Russian roulette (roulette).
// Emission found by a sampled ray carries the matching MIS weight (emission); emission seen by the camera or
// through delta lobes carries weight 1.
// Russian roulette starts after three bounces with survival probability min(1, sqrt(max(beta * eta^2)))
// (the eta^2 factor removes the radiance scaling of refraction from the decision; the square root ends paths later,
// as Cycles does, because a display's tone curve makes dim contributions count for more than their linear share).
// Light leaks through shading normals are prevented by requiring the geometric and shading
// normals to agree on whether a direction pair is reflection or transmission (Veach 1996).
//
// BSSRDFs (Material::subsurface_profile): at a subsurface boundary a transmitted BSDF sample is not
// followed; probe rays (bssrdf/probe_sampling.h) pick the point where the light leaves, weighted by
// R(r) / pdf, and the path goes on from there as a second surface vertex with the material's exit BSDF.
// Probe queries are counted as probe_rays.
//
// Media: a ray travels in the medium of the camera or of the last boundary it crossed (Shape::interior and
// exterior); a shape without a material is an index-matched boundary that rays pass without a vertex.
// Polygon lights (quads, polygons) are sampled by area under MIS, or, with "direct": "ltc", integrated in closed
// form against the BSDF's LTC lobes (Bsdf::ltc_lobes) plus a Monte Carlo estimate of what that misses (shadows,
// the fit's error), which keeps the estimate unbiased (integrators/ltc_direct.h; docs/lights.md); "ltc-ratio" scales
// the closed form by shadowed / unshadowed estimates (Heitz, Hill, McGuire 2018; biased); "ltc-preview" keeps the
// closed form alone.
// Path guiding ("guiding": "on"; Müller, Gross, Novák 2017): at a surface vertex whose BSDF has a diffuse lobe and
// neither delta nor transmission lobes, and where the field has learnt a distribution, the direction is drawn from that distribution
// with probability kGuideFraction and from the BSDF otherwise; the density is the mixture's, in the throughput and in
// every MIS weight (next-event estimation's, and the emission the ray finds). Off under the LTC modes and for BSSRDF
// vertices. In a training pass each guidable vertex records Li/p of its continuation: what the rest of the path
// brought (the MIS-weighted emission its ray found and all after it), divided by the throughput to the vertex and the
// mixture's density. Deviation from the paper, which also records the light samples: next-event estimation already
// takes the direct light, and learning it too sent half of the guided directions to the lights (2.3 times the
// variance on bench/cycles' window-lit interior, docs/performance.md). Purely glossy BSDFs are not guided either: a
// distribution of Li alone (not of its product with the BSDF) sent half of their samples outside their lobes (1.5 and
// 1.9 times the variance on the glossy spheres and the product shot).
#pragma once

#include "integrators/guiding_field.h"
#include "integrators/integrator.h"
#include "scene/scene.h"

namespace kozu {

class PathIntegrator final : public Integrator {
 public:
  PathIntegrator(const Scene& scene, int max_depth, DirectLighting direct = DirectLighting::Sample);
  Rgb li(const Ray& ray, Sampler& sampler, Arena& arena, RayCounters& counters, const StopFlag& stop) const override;
  bool signed_samples() const override { return direct_ == DirectLighting::Ltc; }
  Rgb li_features(const Ray& ray, Sampler& sampler, Arena& arena, RayCounters& counters, const StopFlag& stop,
                  PixelFeatures& features) const override;
  // "ltc" learns its control variate's coefficient from the neighbouring pixels' samples (PixelMemory).
  bool pixel_memory() const override { return direct_ == DirectLighting::Ltc; }
  Rgb li_pixel(const Ray& ray, Sampler& sampler, Arena& arena, RayCounters& counters, const StopFlag& stop,
               PixelFeatures* features, PixelMemory* memory) const override;
  Rgb visible_emission(const Ray& ray, Sampler& sampler, Arena& arena, RayCounters& counters,
                       const StopFlag& stop) const override;
  // Path guiding: surface vertices sample directions from the field's distributions as well as their BSDF's
  // (one-sample MIS); with `record`, every path also adds its vertices' records to the field (a training pass,
  // render/guiding_training.h). Null: off.
  void set_guiding(const GuidingField* field, bool record) {
    guiding_ = field;
    record_ = record && field;
  }

 private:
  const Scene& scene_;
  int max_depth_;
  DirectLighting direct_;
  const GuidingField* guiding_ = nullptr;
  bool record_ = false;
  // "ltc": the lights that may take its control variate: the scene's analytic, untextured polygon lights (a
  // textured light's variation stays in every term, and the control variate only added noise under the
  // stained-glass window, docs/lights.md), the kMaxLtcLights brightest.
  static constexpr size_t kMaxLtcLights = PixelMemory::kMaxLights;
  std::vector<const PolygonLight*> ltc_lights_;
};

}  // namespace kozu
