#include "integrators/path.h"

#include "bssrdf/probe_sampling.h"
#include "core/rng.h"
#include "media/tracking.h"

namespace kozu {

namespace {
// True if the shading frame and the geometric normal agree on whether (wo, wi) is a reflection.
// cos_o_geo = dot(wo, ng), computed once per vertex.
inline bool sides_agree(float cos_o_geo, const Vec3& ng, const Vec3& wi, const Vec3& wo_local, const Vec3& wi_local) {
  const bool geometric_reflection = cos_o_geo * glm::dot(wi, ng) > 0.0f;
  const bool shading_reflection = wo_local.z * wi_local.z > 0.0f;
  return geometric_reflection == shading_reflection;
}

// Crossings of index-matched medium boundaries allowed along one ray (a guard against degenerate geometry).
constexpr int kMaxNullCrossings = 256;

// The medium on the side of si's surface that w points into; the current one if the shape has none.
inline const Medium* medium_after(const SurfaceInteraction& si, const Vec3& w, const Medium* current) {
  if (!si.shape->has_medium_interface()) return current;
  return glm::dot(w, si.ng) > 0.0f ? si.shape->exterior : si.shape->interior;
}

}  // namespace

Rgb PathIntegrator::transmittance(Ray ray, const Medium* medium, Pcg32& rng, RayCounters& counters,
                                  PathBudget& budget) const {
  // Through index-matched boundaries only: any surface with a material blocks.
  Rgb T(1.0f);
  for (int crossing = 0; crossing < kMaxNullCrossings; ++crossing) {
    SurfaceInteraction si;
    ++counters.shadow_rays;
    const bool hit = scene_.intersect(ray, si);
    const float t_end = hit ? si.t : ray.tmax;
    if (medium) T *= ratio_tracking(*medium, ray, t_end, rng, budget);
    if (!hit) return T;
    if (si.shape->material || !si.shape->has_medium_interface() || si.shape->light(si.prim)) return Rgb(0.0f);
    if (is_black(T)) return T;
    medium = medium_after(si, ray.d, medium);
    const Vec3 o = si.spawn_origin(ray.d);
    ray = Ray{o, ray.d, std::max(0.0f, ray.tmax - glm::length(o - ray.o))};
  }
  return Rgb(0.0f);
}

Rgb PathIntegrator::li(const Ray& camera_ray, Sampler& sampler, Arena& arena, RayCounters& counters,
                       const StopFlag& stop) const {
  const LightSampler& lights = scene_.light_sampler();
  Rgb L(0.0f), beta(1.0f);
  Ray ray = camera_ray;
  bool specular_bounce = true;  // camera rays see emitters with weight 1
  float prev_bsdf_pdf = 0.0f;
  float eta_scale = 1.0f;
  LightSampleContext prev_ctx;
  const bool media = scene_.has_media();
  const Medium* medium = scene_.camera_medium;
  // Free-flight sampling, ratio tracking and stochastic phase functions draw an unbounded number of random
  // numbers: a generator seeded from the sampler when the path first needs it.
  Pcg32 rng;
  bool rng_seeded = false;
  auto path_rng = [&]() -> Pcg32& {
    if (!rng_seeded) {
      const Vec4 u = sampler.next_4d();
      rng.seed(mix64((uint64_t(u.x * 4294967296.0f) << 32) ^ uint64_t(u.y * 4294967296.0f)),
               mix64((uint64_t(u.z * 4294967296.0f) << 32) ^ uint64_t(u.w * 4294967296.0f)));
      rng_seeded = true;
    }
    return rng;
  };
  PathBudget budget(&stop);
  // Shadow rays: plain occlusion without media, ratio tracking through index-matched boundaries with them.
  auto shadow_transmittance = [&](const Ray& shadow, const Medium* from) -> Rgb {
    if (!media) {
      ++counters.shadow_rays;
      return scene_.occluded(shadow) ? Rgb(0.0f) : Rgb(1.0f);
    }
    return transmittance(shadow, from, path_rng(), counters, budget);
  };
  int null_crossings = 0;
  bool camera = true;

  for (int depth = 0;; ++depth) {
    if (stop.load(std::memory_order_relaxed)) break;
    SurfaceInteraction si;
    ++(camera ? counters.camera_rays : counters.extension_rays);
    camera = false;
    const bool hit = scene_.intersect(ray, si);

    // Through the medium up to the surface (or to infinity): a real scattering event is a path vertex.
    if (medium) {
      float t_scatter;
      if (sample_free_flight(*medium, ray, hit ? si.t : kInfinity, path_rng(), beta, &t_scatter, budget)) {
        if (depth == max_depth_) break;
        const Vec3 p = ray.o + t_scatter * ray.d;
        const Vec3 wo = -ray.d;
        const PhaseFunction* phase = medium->phase(p, arena);
        const LightSampleContext ctx{p, Vec3(0.0f)};
        const Vec4 u_nee = sampler.next_4d();
        const Vec4 u_scat = sampler.next_4d();
        if (!lights.empty()) {
          float pmf;
          const Light* light = lights.sample(u_nee.z, &pmf);
          const LightSample ls = light->sample(ctx, Vec2(u_nee.x, u_nee.y));
          if (ls.valid() && !is_black(ls.radiance)) {
            const float f = phase->eval(wo, ls.wi, path_rng());
            if (f > 0.0f) {
              Ray shadow{p, ls.wi, kInfinity};
              if (!ls.infinite) {
                const Vec3 target = glm::dot(ls.n, ls.n) > 0.0f
                                        ? offset_point(ls.p, glm::dot(-ls.wi, ls.n) > 0.0f ? ls.n : -ls.n, ls.p_error)
                                        : ls.p;
                shadow.tmax = glm::length(target - p);
              }
              const Rgb T = shadow_transmittance(shadow, medium);
              if (!is_black(T)) {
                const float light_pdf = pmf * ls.pdf;
                const float w = light->is_delta() ? 1.0f : power_heuristic(light_pdf, phase->pdf(wo, ls.wi));
                L += beta * T * ls.radiance * (f * w / light_pdf);
              }
            }
          }
        }
        const PhaseSample ps = phase->sample(wo, Vec2(u_scat.x, u_scat.y), path_rng());
        if (!ps.valid()) break;
        beta *= ps.weight;
        specular_bounce = false;
        prev_bsdf_pdf = ps.pdf;
        prev_ctx = ctx;
        ray = Ray{p, ps.wi, kInfinity};
        if (depth >= 3) {
          const float survive = std::min(1.0f, max_component(beta) * eta_scale);
          if (u_nee.w >= survive) break;
          beta /= survive;
        }
        if (is_black(beta)) break;
        continue;
      }
      if (is_black(beta)) break;
    }

    if (!hit) {
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

    const Material* material = si.shape->material;
    if (!material && si.shape->has_medium_interface() && !si.shape->light(si.prim)) {
      // An index-matched medium boundary: the ray goes on unchanged in the medium on the other side.
      if (++null_crossings > kMaxNullCrossings) {
        ++counters.truncated_paths;  // a cap, like PathBudget's: counted, not silent
        break;
      }
      medium = medium_after(si, ray.d, medium);
      ray = Ray{si.spawn_origin(ray.d), ray.d, kInfinity};
      --depth;
      continue;
    }
    if (depth == max_depth_) break;
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
              const Ray shadow = ls.infinite ? si.spawn_ray(ls.wi) : si.spawn_ray_to(ls.p, ls.n, ls.p_error);
              const Rgb T = shadow_transmittance(shadow, medium_after(si, ls.wi, medium));
              if (!is_black(T)) {
                const float light_pdf = pmf * ls.pdf;
                const float w = light->is_delta() ? 1.0f : power_heuristic(light_pdf, bsdf_pdf);
                L += beta * T * f * ls.radiance * (w / light_pdf);
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
      medium = medium_after(si, wi, medium);
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
  if (budget.exhausted()) ++counters.truncated_paths;
  return L;
}

}  // namespace kozu
