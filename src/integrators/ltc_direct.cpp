#include "integrators/ltc_direct.h"

#include "integrators/shading_sides.h"
#include "lights/ltc_polygon_sampler.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace kozu {

namespace {

// The closed form Σ_k w_k I_L,k ∫_P D_k dω (Heitz et al. 2016 eqs. 3, 11; I_L,k by eqs. 12–15), with each lobe's I_L
// (the light's radiance as the lobe averages it; the radiance itself for an untextured light) and its share of the
// closed form's luminance.
struct ClosedForm {
  Rgb closed{0.0f};
  std::array<Rgb, kMaxLtcLobes> lobe_radiance;
  std::array<float, kMaxLtcLobes> share{};
};

ClosedForm closed_form(const SurfaceInteraction& si, std::span<const LtcLobe> lobes, const PolygonLight& light) {
  const Frame& frame = si.shading;
  std::array<Vec3, Ltc::kMaxVertices> corners;
  const std::span<const Vec3> world = light.corners();
  for (size_t i = 0; i < world.size(); ++i) corners[i] = frame.to_local(world[i] - si.p);
  const std::span<const Vec3> local(corners.data(), world.size());
  ClosedForm cf;
  for (size_t k = 0; k < lobes.size(); ++k) {
    const float integral = lobes[k].ltc.integrate_polygon(local);
    cf.lobe_radiance[k] = light.ltc_radiance(lobes[k].ltc, frame, si.p);
    cf.closed += lobes[k].weight * cf.lobe_radiance[k] * integral;
    cf.share[k] = std::max(luminance(lobes[k].weight * cf.lobe_radiance[k]), 0.0f) * integral;
  }
  return cf;
}

// f̃(ω) = Σ_k w_k I_L,k D_k(ω) at the local direction wl.
Rgb lobes_at(std::span<const LtcLobe> lobes, const std::array<Rgb, kMaxLtcLobes>& lobe_radiance, const Vec3& wl) {
  Rgb f(0.0f);
  for (size_t k = 0; k < lobes.size(); ++k) f += lobes[k].weight * lobe_radiance[k] * lobes[k].ltc.eval(wl);
  return f;
}

}  // namespace

// β of "ltc"'s control variate where the pixel's neighbours have not seen the light (Path::surface_vertex): the
// share of the lobes' closed form that two probe points of the light see,
// Σ f̃ V / p_L over Σ f̃ / p_L (luminance; the points in opposite quarters of the light's sample space, u_probe.x, .y
// and their shift by one half), from numbers no other decision uses. It is 1 where the light is seen whole, 0 in
// umbra, and in a penumbra close to the coefficient that minimises the variance there (the seen share, where
// visibility and the sampled terms are independent). Two probes that pass or fail together (the least of the two,
// as kozu first had it) made the penumbrae noisier than light sampling alone: measured in docs/lights.md. Where a
// glossy lobe shapes the vertex's light samples (shaped), the probes are drawn as they are: f̃ / p_L is then nearly
// constant, so two probes weigh the part of the light the lobe sees instead of two points anywhere on it (on the
// glossy floor with the sphere, 1.9 times less variance than probes by area).
LtcVisibility ltc_probe_visibility(const SurfaceInteraction& si, std::span<const LtcLobe> lobes,
                                   const PolygonLight& light, const LobeLightSampler* shaped,
                                   const LightSampleContext& ctx, const Vec4& u_probe, const LtcShadows& shadows) {
  LtcVisibility v;
  if (!light.faces(si.p)) return v;
  const auto shift = [](float u) { return u < 0.5f ? u + 0.5f : u - 0.5f; };
  for (const Vec2 u : {Vec2(u_probe.x, u_probe.y), Vec2(shift(u_probe.x), shift(u_probe.y))}) {
    const LightSample probe = shaped ? shaped->sample(ctx, u) : light.sample(ctx, u);
    if (!probe.valid()) continue;
    const float g = ltc_visibility_weight(si, lobes, probe);
    if (!(g > 0.0f)) continue;
    v.all += g;
    v.seen += g * std::clamp(luminance(shadows.transmittance(probe.wi, probe.p, probe.p_error)), 0.0f, 1.0f);
  }
  return v;
}

float ltc_visibility_weight(const SurfaceInteraction& si, std::span<const LtcLobe> lobes, const LightSample& ls) {
  if (!ls.valid()) return 0.0f;
  const Vec3 wl = si.shading.to_local(ls.wi);
  float g = 0.0f;
  for (const LtcLobe& l : lobes) g += luminance(l.weight) * l.ltc.eval(wl);
  g /= ls.pdf;
  return g > 0.0f && std::isfinite(g) ? g : 0.0f;
}

Vec3 ltc_toward(const SurfaceInteraction& si, const Vec3& wo_local, const PolygonLight* polygon) {
  const float side = wo_local.z >= 0.0f ? 1.0f : -1.0f;
  if (polygon) {
    const Vec3 d = si.shading.to_local(polygon->centre() - si.p);
    const float len = glm::length(d);
    if (d.z * side > 1e-4f * len) return d / len;
  }
  return Vec3(0.0f, 0.0f, side);
}

// "ltc-ratio" and "ltc-preview" (docs/lights.md): the light's radiance L_e over the polygon P against the BSDF f
// (with its cosine) and the visibility V, from the closed form C of the BSDF's LTC lobes f̃ = Σ_k w_k I_L,k D_k
// (Heitz et al. 2016 eqs. 3, 11; for a textured light I_L,k is the texture as lobe k averages it, eqs. 12–15, the
// prefiltered fetch of lights/ltc_texture.h). "ltc-preview" is C alone, without shadows. "ltc-ratio" is C times
// Σ_j f V L_e / p(ω_j) over Σ_j f̃ / p(ω_j) (Heitz, Hill, McGuire 2018), with one direction from the light (by area,
// density p_A) and one from the lobes (lobe k in proportion to its share of C, then a direction on P from lobe k
// restricted to P, lights/ltc_polygon_sampler.h; density p_D = Σ_k c_k p_k), p = p_A + p_D: consistent, biased.
std::optional<Rgb> ltc_direct(const LtcVertex& v, std::span<const LtcLobe> lobes, const PolygonLight& light,
                              DirectLighting mode, const Vec4& u_light, const Vec4& u_ltc,
                              const LtcShadows& shadows) {
  const SurfaceInteraction& si = v.si;
  if (!light.faces(si.p)) return std::nullopt;
  const Frame& frame = si.shading;
  const ClosedForm cf = closed_form(si, lobes, light);
  const Rgb& closed = cf.closed;
  const std::array<Rgb, kMaxLtcLobes>& lobe_radiance = cf.lobe_radiance;
  std::array<float, kMaxLtcLobes> share = cf.share;
  if (mode == DirectLighting::LtcPreview) return closed;
  // The LTC strategy draws from each lobe restricted to P (a lobe to which P is all but a point, or on which P has
  // no weight, is left out of it: a choice made before any sample, so the estimate stays unbiased).
  std::array<std::array<Vec3, 3>, LtcPolygonSampler::kMaxTriangles> triangles;
  const std::span<const EmitterTriangle> emitters = light.triangles();
  const size_t n_triangles = std::min(emitters.size(), triangles.size());
  for (size_t i = 0; i < n_triangles; ++i) {
    const EmitterTriangle& t = emitters[i];
    triangles[i] = {frame.to_local(t.p0 - si.p), frame.to_local(t.p0 + t.e1 - si.p),
                    frame.to_local(t.p0 + t.e2 - si.p)};
  }
  std::array<std::optional<LtcPolygonSampler>, kMaxLtcLobes> samplers;
  for (size_t k = 0; k < lobes.size(); ++k) {
    if (share[k] > 0.0f) samplers[k].emplace(lobes[k].ltc, std::span(triangles.data(), n_triangles));
    if (!samplers[k] || !samplers[k]->valid()) share[k] = 0.0f;
  }
  float share_sum = 0.0f;
  for (size_t k = 0; k < lobes.size(); ++k) share_sum += share[k];
  const LightSampleContext ctx{si.p, Vec3(0.0f)};
  const auto transmittance_to = [&](const Vec3& w, const Vec3& q, float q_error) {
    return shadows.transmittance(w, q, q_error);
  };
  // f V L / (p_A + p_D) and f̃ / (p_A + p_D) towards the point q (error bound q_error, radiance Lq) of the light, in
  // direction w; f̃ carries each lobe's I_L.
  Rgb f_sum(0.0f), f_tilde_sum(0.0f);
  const auto add = [&](const Vec3& w, const Vec3& q, float q_error, float p_a, const Rgb& Lq) {
    const Vec3 wl = frame.to_local(w);
    const Rgb f_tilde = lobes_at(lobes, lobe_radiance, wl);
    float p_d = 0.0f;
    for (size_t k = 0; k < lobes.size(); ++k)
      if (share[k] > 0.0f) p_d += share[k] / share_sum * samplers[k]->pdf(wl);
    const float p = p_a + p_d;
    if (!(p > 0.0f)) return;
    float unused;
    Rgb f = sides_agree(v.cos_o_geo, si.ng, w, v.wo_local, wl) ? v.bsdf.eval_pdf(v.wo_local, wl, &unused) : Rgb(0.0f);
    if (!is_black(f)) f *= Lq * transmittance_to(w, q, q_error);
    f_sum += f / p;
    f_tilde_sum += f_tilde / p;
  };
  const LightSample ls = light.sample(ctx, Vec2(u_light.x, u_light.y), false);
  if (ls.valid()) add(ls.wi, ls.p, ls.p_error, ls.pdf, ls.radiance);
  if (share_sum > 0.0f) {
    float u = u_ltc.z * share_sum;
    size_t k = 0;
    for (size_t j = 0; j < lobes.size(); ++j) {
      if (!(share[j] > 0.0f)) continue;
      k = j;  // the last lobe with a share, should rounding carry u past every share
      if (u < share[j]) break;
      u -= share[j];
    }
    const Vec3 w = glm::normalize(frame.to_world(samplers[k]->sample(Vec2(u_ltc.x, u_ltc.y))));
    Vec3 q;
    if (light.intersect(si.p, w, &q)) add(w, q, 0.0f, light.pdf_by_area_at(si.p, q), light.radiance_at(q));
  }
  // Heitz, Hill, McGuire 2018: the closed form times shadowed / unshadowed, both from the same two directions.
  Rgb sum(0.0f);
  for (int c = 0; c < 3; ++c) sum[c] = f_tilde_sum[c] > 0.0f ? closed[c] * f_sum[c] / f_tilde_sum[c] : f_sum[c];
  return sum;
}

// "direct": "ltc" (docs/lights.md): the path's own estimate of the light's direct light, light sampling (of this
// light chosen with probability pmf, then a point with density p_L) and BSDF sampling (density p_B) weighted by the
// power heuristic between pmf p_L and p_B as everywhere else (Path::direct_lighting, Path::emission), plus the
// control variate β (C − Ĉ), with C the closed form of the lobes f̃ = Σ_k w_k I_L,k D_k over P and Ĉ its estimate
// from the same two directions with the same weights, without visibility:
//   Ĉ = [light chosen] f̃(ω_L) w_L(ω_L) / (pmf p_L(ω_L))  +  [ω_B meets P] f̃(ω_B) w_B(ω_B) / p_B(ω_B),
//   w_L = (pmf p_L)² / ((pmf p_L)² + p_B²) = 1 − w_B.
// E[Ĉ] = C, so the control variate adds nothing on average whatever β is, as long as β is independent of both
// directions and of the light's choice (what the neighbouring pixels saw, or probes with numbers of their own), and
// pmf, p_L and p_B are those the two directions were drawn with: the lobe-shaped mixture's where one shaped the light
// sample, the guided mixture's where a guide shaped the BSDF's (so w_L + w_B = 1 at every direction). C is added
// whichever light was chosen: where the light is seen whole (β = 1) and f L ≈ f̃, each sampled term f V L w / p is
// cancelled by its Ĉ term, the choice's variance included, and the closed form is left: on an unshadowed Lambertian
// surface lit by this light alone the estimate is exact with one sample. In umbra (β = 0) it is plain sampling and
// the closed form is skipped. ls is the light's sample only where it was the light chosen (invalid otherwise).
// Returns β (C − Ĉ).
Rgb ltc_control_variate(const LtcVertex& v, std::span<const LtcLobe> lobes, const PolygonLight& light, float pmf,
                        const LightSample& ls, float ls_scatter_pdf, const BsdfSample& bs,
                        const LobeLightSampler* shaped, float beta) {
  const SurfaceInteraction& si = v.si;
  if (!(beta > 0.0f) || !(pmf > 0.0f) || !light.faces(si.p)) return Rgb(0.0f);
  const Frame& frame = si.shading;
  const ClosedForm cf = closed_form(si, lobes, light);
  Rgb estimate(0.0f);
  if (ls.valid()) {
    const Vec3 wl = frame.to_local(ls.wi);
    const float w = power_heuristic(pmf * ls.pdf, ls_scatter_pdf);
    estimate += lobes_at(lobes, cf.lobe_radiance, wl) * (w / (pmf * ls.pdf));
  }
  Vec3 q;
  if (bs.valid() && !bs.delta()) {
    const Vec3 w_world = glm::normalize(frame.to_world(bs.wi));
    if (light.intersect(si.p, w_world, &q)) {
      const float p_light = light.pdf_at(si.p, q);
      const float w =
          power_heuristic(bs.pdf, pmf * (shaped && p_light > 0.0f ? shaped->pdf(w_world, p_light) : p_light));
      estimate += lobes_at(lobes, cf.lobe_radiance, glm::normalize(bs.wi)) * (w / bs.pdf);
    }
  }
  return beta * (cf.closed - estimate);
}

}  // namespace kozu
