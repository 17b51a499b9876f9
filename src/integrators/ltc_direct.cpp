#include "integrators/ltc_direct.h"

#include "integrators/shading_sides.h"
#include "lights/ltc_polygon_sampler.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace kozu {

Vec3 ltc_toward(const SurfaceInteraction& si, const Vec3& wo_local, const PolygonLight* polygon) {
  const float side = wo_local.z >= 0.0f ? 1.0f : -1.0f;
  if (polygon) {
    const Vec3 d = si.shading.to_local(polygon->centre() - si.p);
    const float len = glm::length(d);
    if (d.z * side > 1e-4f * len) return d / len;
  }
  return Vec3(0.0f, 0.0f, side);
}

// "direct": "ltc" (docs/lights.md): the light's radiance L_e over the polygon P against the BSDF f (with its
// cosine) and the visibility V, with the BSDF's LTC lobes f̃ = Σ_k w_k D_k as a control variate:
//   ∫_P f V L_e dω = β L_e Σ_k w_k ∫_P D_k dω  +  ∫_P (f V − β f̃) L_e dω   for any β.
// The first term is Heitz et al. 2016's closed form (eqs. 3, 11). The second, what it misses (shadows, the fit's error,
// Fresnel), is estimated with one direction from the light (by area, density p_A) and one from the lobes (lobe k
// in proportion to its share of the closed form, then a direction on P from lobe k restricted to P,
// lights/ltc_polygon_sampler.h; density p_D = Σ_k c_k p_k), combined by the balance heuristic:
// Σ_j (f V − β f̃)(ω_j) L_e / (p_A + p_D)(ω_j). β is the visibility of one more point of the light (a probe
// drawn from numbers of its own): whatever it is, the expectation is the integral, so the sum is unbiased. In
// full light (β = 1) the closed form carries the estimate, and on an unshadowed Lambertian surface (f = f̃) it is
// exact with one sample; in umbra (β = 0, V = 0) it is exactly 0; only penumbrae are noisy. With β = 0 it is
// plain light and LTC sampling under MIS. "ltc-preview" keeps the closed form alone (β = 1, no residual). An
// estimate may be negative (β = 1 where the residual's directions are shadowed): the integrator says so
// (signed_samples) and the film keeps it.
// A textured light: L_e varies over P, so lobe k's closed form is w_k I_L,k ∫_P D_k dω with I_L,k the texture
// as the lobe averages it (Heitz et al. 2016 eqs. 12–15, the prefiltered fetch of lights/ltc_texture.h), and f̃ carries
// the same I_L,k: the control variate still has exactly the closed form's expectation, and the residual carries the
// texture's true value at each sampled point, so the estimate stays unbiased ("ltc-preview" is the approximation).
std::optional<Rgb> ltc_direct(const LtcVertex& v, std::span<const LtcLobe> lobes, const PolygonLight& light,
                              DirectLighting mode, const Vec4& u_light, const Vec4& u_ltc, const Vec4& u_probe,
                              const LtcShadows& shadows) {
  const SurfaceInteraction& si = v.si;
  if (!light.faces(si.p)) return std::nullopt;
  const Frame& frame = si.shading;
  std::array<Vec3, Ltc::kMaxVertices> corners;
  const std::span<const Vec3> world = light.corners();
  for (size_t i = 0; i < world.size(); ++i) corners[i] = frame.to_local(world[i] - si.p);
  const std::span<const Vec3> local(corners.data(), world.size());

  // Per lobe: I_L (the light's radiance as the lobe averages it; the radiance itself for an untextured light).
  Rgb closed(0.0f);
  std::array<Rgb, kMaxLtcLobes> lobe_radiance;
  std::array<float, kMaxLtcLobes> share{};
  float share_sum = 0.0f;
  for (size_t k = 0; k < lobes.size(); ++k) {
    const float integral = lobes[k].ltc.integrate_polygon(local);
    lobe_radiance[k] = light.ltc_radiance(lobes[k].ltc, frame, si.p);
    closed += lobes[k].weight * lobe_radiance[k] * integral;
    share[k] = std::max(luminance(lobes[k].weight * lobe_radiance[k]), 0.0f) * integral;
    share_sum += share[k];
  }
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
  share_sum = 0.0f;
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
    Rgb f_tilde(0.0f);
    float p_d = 0.0f;
    for (size_t k = 0; k < lobes.size(); ++k) {
      f_tilde += lobes[k].weight * lobe_radiance[k] * lobes[k].ltc.eval(wl);
      if (share[k] > 0.0f) p_d += share[k] / share_sum * samplers[k]->pdf(wl);
    }
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
  Rgb sum(0.0f);
  if (mode == DirectLighting::LtcRatio) {
    // Heitz, Hill, McGuire 2018: the closed form times shadowed / unshadowed, both from the same two directions.
    for (int c = 0; c < 3; ++c) sum[c] = f_tilde_sum[c] > 0.0f ? closed[c] * f_sum[c] / f_tilde_sum[c] : f_sum[c];
  } else {
    // β = 1 only when two probes in opposite quarters of the light's sample space both see it: in a penumbra a
    // β of 1 turns each blocked direction into a large negative term, so it is kept for points in full light.
    float cv = 1.0f;
    for (const Vec2 u :
         {Vec2(u_probe.x, u_probe.y), Vec2(std::fmod(u_probe.x + 0.5f, 1.0f), std::fmod(u_probe.y + 0.5f, 1.0f))}) {
      const LightSample probe = light.sample(ctx, u);
      cv = std::min(cv, probe.valid()
                            ? std::clamp(luminance(transmittance_to(probe.wi, probe.p, probe.p_error)), 0.0f, 1.0f)
                            : 0.0f);
      if (cv == 0.0f) break;
    }
    sum = cv * closed + f_sum - cv * f_tilde_sum;
  }
  return sum;
}

}  // namespace kozu
