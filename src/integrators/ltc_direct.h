// "direct": "ltc", "ltc-ratio" and "ltc-preview" (docs/lights.md): the direct light of one polygon light at a
// surface vertex, integrated in closed form against the BSDF's LTC lobes (Heitz, Dupuy, Hill, Neubelt 2016,
// "Real-Time Polygonal-Light Shading with Linearly Transformed Cosines", eqs. 3, 11, 12–15). "ltc" uses it as a
// control variate of light and BSDF sampling, its coefficient the light's seen share (learnt from the neighbouring
// pixels, PixelMemory, or from visibility probes), which keeps it unbiased; "ltc-ratio"
// scales the closed form by shadowed / unshadowed estimates (Heitz, Hill, McGuire 2018, "Combining Analytic Direct
// Illumination and Stochastic Shadows"; biased). The path integrator (path.cpp) calls it where the chosen light is
// an analytic polygon and the BSDF has LTC lobes.
#pragma once

#include "geometry/interaction.h"
#include "integrators/lobe_light_sampler.h"
#include "lights/area.h"
#include "materials/bsdf.h"
#include "scene/render_settings.h"

#include <algorithm>
#include <optional>
#include <span>

namespace kozu {

// The shadow rays the estimate traces, answered by the integrator (its media and ray counters): the transmittance
// from the vertex towards the point q of the light (error bound q_error), in direction w.
class LtcShadows {
 public:
  virtual Rgb transmittance(const Vec3& w, const Vec3& q, float q_error) const = 0;

 protected:
  ~LtcShadows() = default;
};

// The vertex: its interaction, BSDF (in si's shading frame), wo in that frame and dot(wo, ng).
struct LtcVertex {
  const SurfaceInteraction& si;
  const Bsdf& bsdf;
  Vec3 wo_local;
  float cos_o_geo;
};

// The direction (local, on wo's side) to the centre of the polygon light chosen at this vertex, for
// Bsdf::ltc_lobes; the normal on wo's side when there is none or the centre lies on the other side.
Vec3 ltc_toward(const SurfaceInteraction& si, const Vec3& wo_local, const PolygonLight* polygon);

// "ltc-ratio" and "ltc-preview": the estimate of ∫_P f V L_e dω over the light's polygon P (before the path's
// throughput and the light's selection probability); nullopt where the light faces away from the vertex. u_light: a
// point on the light; u_ltc: a lobe (z) and a direction from it (x, y).
std::optional<Rgb> ltc_direct(const LtcVertex& v, std::span<const LtcLobe> lobes, const PolygonLight& light,
                              DirectLighting mode, const Vec4& u_light, const Vec4& u_ltc, const LtcShadows& shadows);

// "ltc"'s coefficient β: the share of the lobes' light that shadow rays saw, Σ f̃ V / p over Σ f̃ / p (luminance of
// f̃ = Σ_k w_k D_k, p the density the ray's point on the light was drawn with). `seen` and `all` are the two sums.
struct LtcVisibility {
  float seen = 0.0f, all = 0.0f;
  float share() const { return all > 0.0f ? std::min(seen / all, 1.0f) : 0.0f; }
};

// Two probe points of the light, drawn with u_probe (numbers no other decision uses) as the vertex's light samples
// are (by `shaped`, where a glossy lobe shapes them, else by the light's own sample()), and what they see.
LtcVisibility ltc_probe_visibility(const SurfaceInteraction& si, std::span<const LtcLobe> lobes,
                                   const PolygonLight& light, const LobeLightSampler* shaped,
                                   const LightSampleContext& ctx, const Vec4& u_probe, const LtcShadows& shadows);

// f̃'s luminance weight of a shadow ray towards the light sample ls (world direction ls.wi, density ls.pdf): the
// term it adds to LtcVisibility::all. 0 where it has none.
float ltc_visibility_weight(const SurfaceInteraction& si, std::span<const LtcLobe> lobes, const LightSample& ls);

// "ltc": the control variate added to the path's light and BSDF sampling of light (chosen with probability pmf at
// the vertex), whichever light was chosen, before the path's throughput. ls: the vertex's sample of this light (drawn
// at ctx; invalid where it was not the light chosen or there was none); bs: its BSDF sample; ls_scatter_pdf: the
// density with which the vertex's own sampling (the BSDF's, or its mixture with a guide) draws ls.wi; shaped: the
// sampler of this light's points, where a glossy lobe shaped it (null: the light's own sample()); beta: the control
// variate's coefficient, which must not depend on the light's choice, ls or bs (the neighbouring pixels'
// LtcVisibility, or the probes'). The densities must be those the samples were drawn with, for E[Ĉ] = C.
Rgb ltc_control_variate(const LtcVertex& v, std::span<const LtcLobe> lobes, const PolygonLight& light, float pmf,
                        const LightSample& ls, float ls_scatter_pdf, const BsdfSample& bs,
                        const LobeLightSampler* shaped, float beta);

}  // namespace kozu
