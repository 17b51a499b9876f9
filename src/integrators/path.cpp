#include "integrators/path.h"

#include "bssrdf/probe_sampling.h"

namespace kozu {

namespace {
// True if the shading frame and the geometric normal agree on whether (wo, wi) is a reflection.
// cos_o_geo = dot(wo, ng), computed once per vertex.
inline bool sides_agree(float cos_o_geo, const Vec3& ng, const Vec3& wi, const Vec3& wo_local, const Vec3& wi_local) {
  const bool geometric_reflection = cos_o_geo * glm::dot(wi, ng) > 0.0f;
  const bool shading_reflection = wo_local.z * wi_local.z > 0.0f;
  return geometric_reflection == shading_reflection;
}
}  // namespace

Rgb PathIntegrator::li(const Ray& camera_ray, Sampler& sampler, Arena& arena, RayCounters& counters) const {
  const LightSampler& lights = scene_.light_sampler();
  Rgb L(0.0f), beta(1.0f);
  Ray ray = camera_ray;
  bool specular_bounce = true;  // camera rays see emitters with weight 1
  float prev_bsdf_pdf = 0.0f;
  float eta_scale = 1.0f;
  LightSampleContext prev_ctx;

  for (int depth = 0;; ++depth) {
    SurfaceInteraction si;
    ++(depth == 0 ? counters.camera_rays : counters.extension_rays);
    if (!scene_.intersect(ray, si)) {
      for (const InfiniteLight* env : scene_.infinite_lights()) {
        const Rgb Le = env->radiance(ray.d);
        if (specular_bounce) {
          L += beta * Le;
        } else {
          const float light_pdf = lights.pmf(env) * env->pdf(prev_ctx, ray.d);
          L += beta * Le * power_heuristic(prev_bsdf_pdf, light_pdf);
        }
      }
      break;
    }

    if (const Light* light = si.shape->light(si.prim)) {
      const auto* area = static_cast<const AreaLight*>(light);
      const Rgb Le = area->radiance(si);
      if (!is_black(Le)) {
        if (specular_bounce) {
          L += beta * Le;
        } else {
          const float light_pdf = lights.pmf(light) * area->pdf(prev_ctx, si);
          L += beta * Le * power_heuristic(prev_bsdf_pdf, light_pdf);
        }
      }
    }

    if (depth == max_depth_) break;
    const Material* material = si.shape->material;
    if (!material) break;  // emitter without a surface material absorbs
    const Bsdf* bsdf = material->bsdf(si, arena);
    const RgbProfile* profile = material->subsurface_profile();

    // One scattering vertex, or two when the path passes through a BSSRDF: the boundary at si, then
    // the exit BSDF at the probe's point.
    bool alive = false;
    float u_rr = 0.0f;
    for (;;) {
      const Frame& frame = si.shading;
      const Vec3 wo_local = frame.to_local(si.wo);
      const float cos_o_geo = glm::dot(si.wo, si.ng);
      const uint32_t bsdf_flags = bsdf->flags();

      // The context for light sampling: the normal on wo's side for reflection-only BSDFs (lets a
      // uniform environment sample the visible hemisphere), none when light may be transmitted.
      LightSampleContext ctx{si.p, Vec3(0.0f)};
      if (!(bsdf_flags & kBsdfTransmission)) ctx.n = wo_local.z >= 0.0f ? frame.n : -frame.n;

      // Two 4D points per vertex, drawn at every vertex so that dimensions line up: the 2D choices
      // (point on the light, BSDF direction) take Sobol dimensions 0 and 1, the best stratified pair.
      const Vec4 u_nee = sampler.next_4d();   // light point (x, y), light choice (z), roulette (w)
      const Vec4 u_scat = sampler.next_4d();  // BSDF direction (x, y), lobe (z)
      const float u_light = u_nee.z, u_lobe = u_scat.z;
      u_rr = u_nee.w;
      const Vec2 u_light2(u_nee.x, u_nee.y), u_bsdf(u_scat.x, u_scat.y);

      // Next-event estimation.
      if (has_non_delta(bsdf_flags) && !lights.empty()) {
        float pmf;
        const Light* light = lights.sample(u_light, &pmf);
        const LightSample ls = light->sample(ctx, u_light2);
        if (ls.valid() && !is_black(ls.radiance)) {
          const Vec3 wi_local = frame.to_local(ls.wi);
          if (sides_agree(cos_o_geo, si.ng, ls.wi, wo_local, wi_local)) {
            float bsdf_pdf;
            const Rgb f = bsdf->eval_pdf(wo_local, wi_local, &bsdf_pdf);
            if (!is_black(f)) {
              const Ray shadow = ls.infinite ? si.spawn_ray(ls.wi) : si.spawn_ray_to(ls.p, ls.n);
              ++counters.shadow_rays;
              if (!scene_.occluded(shadow)) {
                const float light_pdf = pmf * ls.pdf;
                const float w = light->is_delta() ? 1.0f : power_heuristic(light_pdf, bsdf_pdf);
                L += beta * f * ls.radiance * (w / light_pdf);
              }
            }
          }
        }
      }

      // BSDF sampling.
      const BsdfSample bs = bsdf->sample(wo_local, u_lobe, u_bsdf);
      if (!bs.valid() || is_black(bs.f)) break;

      if (profile && (bs.flags & kBsdfTransmission)) {
        // Into the BSSRDF: the refracted direction is not followed; probe rays find where the light
        // leaves (bssrdf/probe_sampling.h), and the path goes on from there through the exit BSDF.
        ProbeSample ps;
        if (!sample_probe(scene_.accel(), si, *profile, sampler.next_4d(), &ps, &counters.probe_rays)) break;
        beta *= bs.weight() * ps.weight;
        if (is_black(beta)) break;
        si = ps.si;
        si.wo = si.ng;  // light leaves on the front side; the exit BSDF ignores wo otherwise
        bsdf = material->subsurface_exit_bsdf(arena);
        profile = nullptr;
        continue;
      }

      const Vec3 wi = glm::normalize(frame.to_world(bs.wi));
      if (!sides_agree(cos_o_geo, si.ng, wi, wo_local, bs.wi)) break;
      beta *= bs.f / bs.pdf;
      specular_bounce = bs.delta();
      prev_bsdf_pdf = bs.pdf;
      prev_ctx = ctx;
      if (bs.flags & kBsdfTransmission) eta_scale *= bs.eta * bs.eta;
      ray = si.spawn_ray(wi);
      alive = true;
      break;
    }
    if (!alive) break;

    if (depth >= 3) {
      const float survive = std::min(1.0f, max_component(beta) * eta_scale);
      if (u_rr >= survive) break;
      beta /= survive;
    }
    if (is_black(beta)) break;
  }
  return L;
}

}  // namespace kozu
