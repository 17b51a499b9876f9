#include "integrators/path.h"

#include "bssrdf/probe_sampling.h"
#include "core/rng.h"
#include "geometry/ray_cone.h"
#include "integrators/lobe_light_sampler.h"
#include "integrators/ltc_direct.h"
#include "integrators/shading_sides.h"
#include "lights/area.h"
#include "media/equiangular.h"
#include "media/homogeneous_flight.h"
#include "media/tracking.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <optional>

#include <type_traits>

namespace kozu {

namespace {
// Crossings of index-matched medium boundaries allowed along one ray (a guard against degenerate geometry).
constexpr int kMaxNullCrossings = 256;
// Russian roulette starts at this depth (path.h).
constexpr int kRouletteDepth = 3;
// Path guiding (path.h): the share of directions drawn from the learnt distribution, the paper's fixed 50 % (Müller,
// Gross, Novák 2017 §5); and the vertices of one path that a training pass records (deeper ones are not).
constexpr float kGuideFraction = 0.5f;
constexpr int kMaxRecordedVertices = 32;
// The length of a medium's axis in the normal feature (Path::medium_vertex).
constexpr float kMediumAxisWeight = 0.5f;

// The medium on the side of si's surface that w points into; the current one if the shape has none.
inline const Medium* medium_after(const SurfaceInteraction& si, const Vec3& w, const Medium* current) {
  if (!si.shape->has_medium_interface()) return current;
  return glm::dot(w, si.ng) > 0.0f ? si.shape->exterior : si.shape->interior;
}

// A vertex's value towards a light: BSDF f |cos| (Rgb) or phase f_p (float); zero means no contribution.
inline bool no_contribution(const Rgb& f) { return is_black(f); }
inline bool no_contribution(float f) { return !(f > 0.0f); }

struct ShadowRay {
  Ray ray;
  const Medium* medium;  // the medium the ray starts in
  float width = 0;       // the vertex's footprint, where the shadow ray's cone starts (Path::light_cone)
};

// A medium vertex a free flight found ("volume_sampling": "mis"): its ray segment and the flight's density there
// (homogeneous media) or its stand-in (the others, Path::tracked_flight), for the MIS weights of its direct light
// against equiangular sampling.
struct FlightVertex {
  bool active = false;
  Vec3 o{0.0f}, d{0.0f};
  float t_max = 0, t = 0, pdf = 0;
  // The segment's equiangular density towards the light equiangular_direct aimed at (null: none), which
  // flight_weight reuses for that light instead of building it again.
  const Light* aimed = nullptr;
  Equiangular eq;
};

// One path: its state and the vertices it passes through.
class Path {
 public:
  Path(const Scene& scene, const Ray& camera_ray, Sampler& sampler, Arena& arena, RayCounters& counters,
       const StopFlag& stop, DirectLighting direct, const GuidingField* guiding = nullptr, bool record = false)
      : scene_(scene),
        sampler_(sampler),
        arena_(arena),
        counters_(counters),
        stop_(stop),
        budget_(&stop),
        ray_(camera_ray),
        medium_(scene.camera_medium),
        cone_(scene.camera.pixel_cone()),
        paths_(static_cast<float>(std::max(scene.settings.spp, 1))),
        direct_(direct),
        guiding_(direct == DirectLighting::Sample ? guiding : nullptr),
        record_(record && guiding_) {}

  // Traces rays until the path ends: absorbed, lost to roulette, escaped, at max_depth, or stopped.
  Rgb trace(int max_depth);
  void record_features(PixelFeatures* f) { features_ = f; }
  // What the pixel's neighbours taught, and where this sample's lessons go (PixelMemory; null: none kept).
  void use_memory(PixelMemory* m) { memory_ = m; }
  // "ltc": the lights that may take its control variate (PathIntegrator::ltc_lights_).
  void use_ltc_lights(std::span<const PolygonLight* const> lights) { ltc_lights_ = lights; }
  // "ltc": whether a vertex took the control variate, and what they added (the path's estimate less it is
  // "sample"'s along the same path: PixelMemory).
  bool cv_taken() const { return cv_taken_; }
  const Rgb& cv_added() const { return cv_added_; }
  // Only the emission seen through perfectly specular vertices (PathIntegrator::visible_emission).
  void visible_emission_only() { emission_only_ = true; }

 private:
  bool homogeneous_flight(const MediumProperties& mp, float t_max, bool equiangular, float* t_scatter);
  bool tracked_flight(float t_max, bool equiangular, float* t_scatter);
  template <class Along>
  void equiangular_direct(float t_max, const Vec4& u, Along&& along);
  float flight_weight(const FlightVertex& v, const Light& light) const;
  ShadowRay medium_shadow(const Vec3& p, float width, const LightSample& ls) const;
  RayCone light_cone(float width, const Light& light, float pdf) const;
  // The level of detail of the current medium where the current ray has gone t (Medium::level_for).
  const Medium& medium_at(float t) const { return *medium_->level_for(cone_.width_at(t)).medium; }
  bool medium_vertex(float t, int depth);
  bool surface_vertex(SurfaceInteraction& si, const Material& material, int depth);
  template <class Scatter, class Shadow>
  LightSample direct_lighting(const LightSampleContext& ctx, const Vec4& u, const Light* light, float pmf,
                              Scatter&& scatter, Shadow&& shadow, float weight = 1.0f,
                              const LobeLightSampler* shaped = nullptr, float* visibility = nullptr);
  const Light* choose_light(const LightSampleContext& ctx, float u, float* pmf) const;
  float light_pmf(const LightSampleContext& ctx, const Light& light) const;
  void emission(const Light& light, const LightHit& hit);
  void continue_path(const Ray& ray, float pdf, bool specular, const LightSampleContext& ctx);
  bool roulette(int depth, float u);
  void spread_cone(const SurfaceInteraction& si, const BsdfSample& bs);
  Rgb shadow_transmittance(Ray ray, const Medium* medium, RayCone cone = {});
  Pcg32& rng();
  // Path guiding (path.h): whether a vertex with these BSDF flags is guided (and recorded), its distribution (null
  // where the field has none yet), and the BSDF sample drawn from the mixture.
  bool guidable(uint32_t bsdf_flags, const RgbProfile* profile) const {
    return guiding_ && !profile && (bsdf_flags & kBsdfDiffuse) && !(bsdf_flags & (kBsdfSpecular | kBsdfTransmission)) &&
           !emission_only_;
  }
  BsdfSample guided_sample(const Bsdf& bsdf, const Frame& frame, const Vec3& wo_local, const Vec4& u,
                           const DirectionalQuadtree* guide) const;
  static float mixture_pdf(const DirectionalQuadtree* guide, const Vec3& wi, float bsdf_pdf) {
    return guide ? kGuideFraction * guide->pdf(wi) + (1.0f - kGuideFraction) * bsdf_pdf : bsdf_pdf;
  }
  void record_vertex(const Vec3& p, const Vec3& d, float value);
  void record_path();
  // The shadow rays of "direct": "ltc" (integrators/ltc_direct.h) towards a polygon light from the vertex si.
  class PathShadows final : public LtcShadows {
   public:
    PathShadows(Path& path, const SurfaceInteraction& si, const PolygonLight& light)
        : path_(path), si_(si), light_(light) {}
    Rgb transmittance(const Vec3& w, const Vec3& q, float q_error) const override {
      // The footprint's own width (no lobe: LTC's integral stands for every direction to the polygon at once).
      return path_.shadow_transmittance(si_.spawn_ray_to(q, light_.normal(), q_error),
                                        medium_after(si_, w, path_.medium_), RayCone{si_.cone_width, 0.0f});
    }

   private:
    Path& path_;
    const SurfaceInteraction& si_;
    const PolygonLight& light_;
  };

  const Scene& scene_;
  Sampler& sampler_;
  Arena& arena_;
  RayCounters& counters_;
  const StopFlag& stop_;
  PathBudget budget_;

  Rgb L_{0.0f}, beta_{1.0f};
  Ray ray_;
  const Medium* medium_;
  bool specular_bounce_ = true;  // camera rays see emitters with weight 1
  bool visible_ = true;  // every vertex so far was perfectly specular: emission found is PixelFeatures::emission
  bool emission_only_ = false;
  float prev_pdf_ = 0.0f;        // density of the last sampled direction, for MIS on the emission it finds
  LightSampleContext prev_ctx_;  // the vertex it was sampled at
  float eta_scale_ = 1.0f;
  Pcg32 rng_;
  bool rng_seeded_ = false;
  // The current ray's cone, for texture footprints (geometry/ray_cone.h); a pinhole's cones start with width 0.
  RayCone cone_;
  float paths_;  // paths per pixel (1 for a render until a time limit), for cones after sampled bounces
  DirectLighting direct_;
  const GuidingField* guiding_;
  bool record_;
  // A training pass's guided vertices: where, which way, the mixture's density, and the throughput and radiance
  // after the vertex's own next-event estimate, from which record_path() finds what the rest of the path brought.
  struct RecordedVertex {
    Vec3 p, wi;
    float pdf;
    Rgb beta, L;
  };
  std::array<RecordedVertex, kMaxRecordedVertices> recorded_;
  int n_recorded_ = 0;
  // "ltc": the light that takes the control variate at a vertex with LTC lobes (ltc_direct.h), of the scene's
  // candidates (PathIntegrator: its analytic, untextured polygon lights): the one the pixel's neighbours learnt about
  // (PixelMemory), else the only one, else the one most likely chosen there (the light hierarchy's pmf is the dearer
  // part of a vertex, so it is asked only then). Never a function of this sample's numbers. Returned as PixelMemory
  // names it: its place in ltc_lights_ plus one; 0 where none can be chosen.
  uint32_t ltc_light(const LightSampleContext& ctx) const;
  // The last vertex had LTC lobes in "ltc-ratio" or "ltc-preview": analytic polygon lights found by its BSDF ray do
  // not count (their closed form took all of the chosen light's).
  bool prev_ltc_ = false;
  // "light_sampling": "lobe" (integrators/lobe_light_sampler.h): whether a vertex with these BSDF flags shapes its
  // light samples of flat area lights by its narrowest LTC lobe; a choice made per vertex and light before any sample,
  // alike at both ends of the MIS (Path::emission asks it again of the last vertex, ShapingQuery), so the estimate
  // stays unbiased.
  bool shapes_light_samples(uint32_t bsdf_flags) const {
    return (direct_ == DirectLighting::Sample || direct_ == DirectLighting::Ltc) &&
           scene_.settings.lobe_light_sampling && (bsdf_flags & kBsdfGlossy) && visible_ && !emission_only_;
  }
  struct ShapingQuery {
    const Bsdf* bsdf = nullptr;  // null: the last vertex did not shape its light samples
    Vec3 wo_local{0.0f};
    Frame frame;
    Vec3 p{0.0f};
    // The vertex's sampler for light, built in *out (its valid() says whether it takes part); nothing where the
    // BSDF has no lobe smooth enough to ask for (the cheap test before its lobes). The one place that decides, for
    // the vertex's own light sample and for Path::emission alike.
    void shape(const DiffuseAreaLight& light, std::optional<LobeLightSampler>* out) const {
      if (bsdf->narrowest_ltc_alpha() > LobeLightSampler::kMaxAlpha) return;
      std::array<LtcLobe, kMaxLtcLobes> lobes;
      const int n = bsdf->ltc_lobes_at_normal(wo_local, lobes.data());
      out->emplace(frame, p, std::span<const LtcLobe>(lobes.data(), size_t(n)), light);
    }
  } prev_shaping_;
  // The last surface vertex's sampler for the light it chose (none where it did not shape), which Path::emission
  // reuses when its BSDF ray meets that light.
  std::optional<LobeLightSampler> shaped_;
  const Light* shaped_light_ = nullptr;
  // The density of the last vertex's light sampling of light towards wi, whose own density there is light_pdf.
  float shaped_light_pdf(const Light& light, const Vec3& wi, float light_pdf) const;
  // The current vertex and the last one, when free flights found them with "volume_sampling": "mis": their direct
  // light is weighed against equiangular sampling.
  FlightVertex flight_, prev_flight_;
  // The current segment's equiangular density and the light it aims at, set by equiangular_direct (null: none), for
  // the flight vertex the segment may make.
  const Light* aimed_ = nullptr;
  Equiangular aimed_eq_;
  // Material surface occlusion (materials/surface_occlusion_material.h) of the last sampled continuation: the factor
  // on the emission its ray meets (direct light) and the one on everything else it brings (indirect light), which
  // settle_occlusion() moves into the throughput once the direct emission is counted.
  float occlusion_direct_ = 1.0f, occlusion_indirect_ = 1.0f;
  void settle_occlusion() {
    beta_ *= occlusion_indirect_;
    occlusion_direct_ = occlusion_indirect_ = 1.0f;
  }
  PixelFeatures* features_ = nullptr;                // where the first vertex's features go (AOVs), if asked
  PixelMemory* memory_ = nullptr;                    // the pixel's memory ("ltc"'s coefficient), if kept
  std::span<const PolygonLight* const> ltc_lights_;  // "ltc": the lights that may take its control variate
  bool cv_taken_ = false;
  Rgb cv_added_{0.0f};
  // Features pass through perfectly specular vertices (mirrors, smooth glass): albedo and normal come from the first
  // vertex that is not, the albedo times the specular weights on the way (the convention of the auxiliary buffers
  // denoisers take), so that what a mirror shows has edges the denoiser can keep. Position and depth stay the first
  // hit's.
  static constexpr int kFeatureDeltas = 4;
  int feature_deltas_ = 0;  // specular vertices passed
  Rgb feature_beta_{1.0f};
  Vec3 feature_p_{0.0f};  // the first hit, once a specular vertex was passed
  void set_features(const Rgb& albedo, const Vec3& normal, const Vec3& p) {
    const Vec3 first = feature_deltas_ > 0 ? feature_p_ : p;
    features_->albedo = albedo * feature_beta_;
    features_->normal = normal;
    features_->position = first;
    features_->depth = glm::dot(first - scene_.camera.position(), scene_.camera.forward());
    features_->set = true;
  }
};

Rgb Path::trace(int max_depth) {
  int null_crossings = 0;
  bool camera = true;
  for (int depth = 0;; ++depth) {
    if (stop_.load(std::memory_order_relaxed)) break;
    SurfaceInteraction si;
    ++(camera ? counters_.camera_rays : counters_.extension_rays);
    const bool hit = camera ? scene_.intersect_camera(ray_, si) : scene_.intersect(ray_, si);
    if (hit) {
      si.cone_width = cone_.width_at(si.t);
      si.fine_filtering = visible_;
    }
    const bool camera_ray = camera;
    camera = false;

    // Through the medium up to the surface (or to infinity): a real scattering event is a path vertex.
    if (medium_) {
      float t_scatter;
      const MediumProperties* h = medium_->homogeneous();
      const bool equiangular = depth < max_depth && scene_.settings.volume_mis;
      if (h ? homogeneous_flight(*h, hit ? si.t : kInfinity, equiangular, &t_scatter)
            : tracked_flight(hit ? si.t : kInfinity, equiangular, &t_scatter)) {
        settle_occlusion();  // light scattered on the way is indirect
        if (depth == max_depth || !medium_vertex(t_scatter, depth)) break;
        continue;
      }
      if (is_black(beta_)) break;
    }

    if (!hit) {
      for (const Light* env : scene_.infinite_lights())
        if (env->camera_visible || !camera_ray) emission(*env, LightHit{ray_.d});
      break;
    }
    const Light* light = si.shape->light(si.prim);
    if (light) emission(*light, LightHit{ray_.d, &si});

    const Material* material = si.shape->material;
    if (!material && si.shape->has_medium_interface() && !light) {
      // An index-matched medium boundary: the ray goes on unchanged in the medium on the other side.
      if (++null_crossings > kMaxNullCrossings) {
        ++counters_.truncated_paths;  // a cap, like PathBudget's: counted, not silent
        break;
      }
      medium_ = medium_after(si, ray_.d, medium_);
      ray_ = Ray{si.spawn_origin(ray_.d), ray_.d, kInfinity};
      cone_.width = si.cone_width;
      --depth;
      continue;
    }
    if (features_ && !features_->set && (depth == max_depth || !material))
      set_features(Rgb(0.0f), si.shading.n * (glm::dot(si.shading.n, si.wo) >= 0.0f ? 1.0f : -1.0f), si.p);
    if (depth == max_depth || !material) break;  // an emitter without a surface material absorbs
    settle_occlusion();                          // what this vertex reflects is indirect light for the one before
    // The visible emission alone goes on through specular vertices only: a material that never makes one ends the
    // path here, before its normal map and BSDF are looked up (most of the re-estimation's time on textured scenes).
    if (emission_only_ && !material->may_be_specular()) break;
    if (!surface_vertex(si, *material, depth)) break;
  }
  if (features_ && !features_->set) {
    // Escaped (or stopped): the background's features, at the first hit when a mirror showed the background.
    if (feature_deltas_ > 0)
      set_features(Rgb(0.0f), Vec3(0.0f), feature_p_);
    else
      features_->set = true;
  }
  if (budget_.exhausted()) ++counters_.truncated_paths;
  counters_.tentative_collisions += budget_.used();
  if (record_) record_path();
  return L_;
}

// The BSDF sample of a guided vertex: from the learnt distribution with probability kGuideFraction (u.w), from the
// BSDF otherwise; its value is the BSDF's and its density the mixture's (one-sample MIS, Veach 1997 §9.2.4), which
// keeps f / pdf unbiased whichever strategy drew it.
BsdfSample Path::guided_sample(const Bsdf& bsdf, const Frame& frame, const Vec3& wo_local, const Vec4& u,
                               const DirectionalQuadtree* guide) const {
  if (!guide || u.w >= kGuideFraction) {
    BsdfSample bs = bsdf.sample(wo_local, u.z, Vec2(u.x, u.y));
    if (guide && bs.valid()) bs.pdf = mixture_pdf(guide, frame.to_world(bs.wi), bs.pdf);
    return bs;
  }
  float unused = 0.0f;
  const Vec3 wi = guide->sample(Vec2(u.x, u.y), &unused);
  BsdfSample bs;
  bs.wi = frame.to_local(wi);
  float bsdf_pdf = 0.0f;
  bs.f = bsdf.eval_pdf(wo_local, bs.wi, &bsdf_pdf);
  // The mixture's density through pdf(), not sample's own: the one function of the direction that the other
  // strategies' weights use too (the two differ within float rounding of a cell's edge).
  bs.pdf = mixture_pdf(guide, wi, bsdf_pdf);
  bs.flags = kBsdfReflection | (bsdf.flags() & (kBsdfDiffuse | kBsdfGlossy));
  return bs;
}

// One record: the hash of where and what dithers the field's fixed-point sums (guiding_field.h), so that a record
// is the same whichever thread adds it.
void Path::record_vertex(const Vec3& p, const Vec3& d, float value) {
  uint32_t bits[4];
  std::memcpy(bits, &p, sizeof(Vec3));
  std::memcpy(&bits[3], &value, sizeof(float));
  const uint64_t h = mix64((uint64_t(bits[0]) << 32 | bits[1]) ^ mix64(uint64_t(bits[2]) << 32 | bits[3]));
  guiding_->record(p, d, value, uint32_t(h >> 32));
}

// At the path's end, each recorded vertex's continuation: the radiance the path gathered after it, over the
// throughput up to it (per channel: later vertices only multiplied it), is Li along its direction; Li / p is the
// record. Roulette's and the later vertices' weights are in it, so it is unbiased.
void Path::record_path() {
  for (int k = 0; k < n_recorded_; ++k) {
    const RecordedVertex& v = recorded_[k];
    const Rgb gathered = L_ - v.L;
    float li = 0.0f;
    for (int c = 0; c < 3; ++c)
      if (v.beta[c] > 0.0f) li += gathered[c] / v.beta[c];
    const float value = li * (1.0f / 3.0f) / v.pdf;
    record_vertex(v.p, v.wi, std::isfinite(value) ? std::max(value, 0.0f) : 0.0f);
  }
  n_recorded_ = 0;
}

// A free flight along the current ray through a homogeneous medium up to t_max (media/homogeneous_flight.h); true
// with *t_scatter where it scattered. With equiangular set ("volume_sampling": "mis", and the flight may make a vertex
// that takes direct light), the direct light scattered along the ray is also estimated by equiangular sampling,
// weighed against the flights' own by MIS over distance (Kulla & Fajardo 2012 §4.2): together unbiased, each where
// it is better — free flights where transmittance dominates, equiangular sampling near a light.
bool Path::homogeneous_flight(const MediumProperties& mp, float t_max, bool equiangular, float* t_scatter) {
  // The sampler's numbers, not the path's generator: stratified distances are what make single scattering converge
  // (a 28× lower variance measured on the lit box's first bounce). Both points are drawn whether or not the
  // equiangular sample is taken, so that the flight's dimensions do not depend on it.
  const Vec4 u_direct = sampler_.next_4d();  // light point (x, y), light choice (z), equiangular distance (w)
  const Vec4 u_flight = sampler_.next_4d();  // distance (x), channel (y)
  const HomogeneousFlight flight(mp.sigma_t, beta_);
  aimed_ = nullptr;
  if (equiangular && !emission_only_)
    equiangular_direct(t_max, u_direct, [&](float t, float* pdf_distance) {
      const Rgb T = flight.transmittance(t);
      *pdf_distance = flight.pdf_of(T);
      return mp.sigma_s * T;
    });
  if (!budget_.step()) {
    beta_ = Rgb(0.0f);
    return false;
  }
  const float t = flight.sample(u_flight.y, u_flight.x);
  if (t < t_max) {
    const Rgb T = flight.transmittance(t);
    const float pdf = flight.pdf_of(T);
    beta_ *= mp.sigma_s * T / pdf;
    flight_ = FlightVertex{equiangular, ray_.o, ray_.d, t_max, t, pdf, aimed_, aimed_eq_};
    *t_scatter = t;
    return true;
  }
  const Rgb T = flight.transmittance(t_max);
  beta_ *= T / flight.pass_probability_of(T);
  return false;
}

// A free flight through a heterogeneous (or microflake) medium by spectral tracking (media/tracking.h); true with
// *t_scatter where it scattered. With equiangular set, the direct light scattered along the ray is also estimated by
// equiangular sampling, the transmittance to its point by ratio tracking. The flight's own density there has no closed
// form, so the MIS weights between the two use a stand-in, the mean σt at the point: any weights that sum to one for
// every distance keep the sum unbiased (Veach 1997 §9.2), and these are that, computed alike on both sides.
bool Path::tracked_flight(float t_max, bool equiangular, float* t_scatter) {
  const auto stand_in = [](const MediumProperties& mp) {
    return (mp.sigma_t.r + mp.sigma_t.g + mp.sigma_t.b) * (1.0f / 3.0f);
  };
  // The walks' first numbers from the sampler, stratified across the pixel's samples (tracking.h, WalkUniforms).
  const Vec4 u_direct = sampler_.next_4d();  // light point (x, y), light choice (z), equiangular distance (w)
  const Vec4 u_walk = sampler_.next_4d();  // the flight's first collision and event (x, y); the ratio tracking's (z, w)
  aimed_ = nullptr;
  if (equiangular && !emission_only_) {
    equiangular_direct(t_max, u_direct, [&](float t, float* pdf_distance) {
      const MediumProperties mp = medium_at(t).properties(ray_.at(t), ray_.d);
      *pdf_distance = stand_in(mp);
      return is_black(mp.sigma_s)
                 ? Rgb(0.0f)
                 : mp.sigma_s *
                       ratio_tracking(*medium_, ray_, t, WalkUniforms(rng(), Vec2(u_walk.z, u_walk.w)), budget_, cone_);
    });
  }
  if (!sample_free_flight(*medium_, ray_, t_max, WalkUniforms(rng(), Vec2(u_walk.x, u_walk.y)), beta_, t_scatter,
                          budget_, cone_))
    return false;
  if (equiangular) {
    const float pdf = stand_in(medium_at(*t_scatter).properties(ray_.at(*t_scatter), ray_.d));
    flight_ = FlightVertex{true, ray_.o, ray_.d, t_max, *t_scatter, pdf, aimed_, aimed_eq_};
  }
  return true;
}

// The direct light scattered along the current ray in [0, t_max), by a distance drawn equiangularly towards a chosen
// light's aim point (media/equiangular.h) and that light sampled from there (u: light point x, y, light choice z,
// distance w); MIS-weighted against the free flight's density. along(t, &pdf) gives σs T(0, t) per channel (exact or
// estimated) and the free flight's density at t (or its stand-in). Lights without an aim point (infinite ones) are
// left to the free flights' vertices, whose weight for them is 1 (flight_weight).
template <class Along>
void Path::equiangular_direct(float t_max, const Vec4& u, Along&& along) {
  // Among the lights with an aim point, by power: the choice must not depend on where along the segment the
  // point falls, and the MIS weights against the flight's vertices are over distance alone (flight_weight).
  float pmf = 0.0f;
  const Light* light = scene_.aim_sampler().sample(u.z, &pmf);
  Vec3 aim;
  if (!light || !light->aim_point(&aim)) return;
  const Equiangular eq(ray_.o, ray_.d, 0.0f, t_max, aim);
  if (!eq.valid()) return;
  aimed_ = light;
  aimed_eq_ = eq;
  const float t = eq.sample(u.w);
  const float pdf = eq.pdf(t);
  if (!(pdf > 0.0f)) return;
  const Vec3 p = ray_.o + t * ray_.d;
  const LightSample ls = light->sample(LightSampleContext{p, Vec3(0.0f)}, Vec2(u.x, u.y));
  if (!ls.valid() || is_black(ls.radiance)) return;
  const float f = medium_at(t).phase(p, arena_)->eval(-ray_.d, ls.wi, rng());
  if (!(f > 0.0f)) return;
  float pdf_distance = 0.0f;
  const Rgb attenuation = along(t, &pdf_distance);
  if (is_black(attenuation)) return;
  const ShadowRay s = medium_shadow(p, cone_.width_at(t), ls);
  const Rgb T = shadow_transmittance(s.ray, s.medium, light_cone(s.width, *light, pmf * ls.pdf));
  if (is_black(T)) return;
  // Light sampling alone at this point (no phase-sampled counterpart): its weight against the phase function is 1.
  const float w = power_heuristic(pdf, pdf_distance);
  L_ += beta_ * attenuation * T * ls.radiance * (f * w / (pdf * pmf * ls.pdf));
}

// The MIS weight, against equiangular sampling towards light, of the direct light a free-flight vertex v takes from
// light (by light sampling or by its phase-sampled ray): 1 for vertices no free flight found with "volume_sampling":
// "mis" and for lights equiangular_direct does not aim at.
float Path::flight_weight(const FlightVertex& v, const Light& light) const {
  Vec3 aim;
  if (!v.active) return 1.0f;
  if (v.aimed == &light) return power_heuristic(v.pdf, v.eq.pdf(v.t));
  if (!light.aim_point(&aim)) return 1.0f;
  const Equiangular eq(v.o, v.d, 0.0f, v.t_max, aim);
  return eq.valid() ? power_heuristic(v.pdf, eq.pdf(v.t)) : 1.0f;
}

// The shadow ray from the medium point p towards the light sample ls, ending just before the light's surface.
ShadowRay Path::medium_shadow(const Vec3& p, float width, const LightSample& ls) const {
  Ray shadow{p, ls.wi, kInfinity};
  if (!ls.infinite) {
    const Vec3 target = glm::dot(ls.n, ls.n) > 0.0f
                            ? offset_point(ls.p, glm::dot(-ls.wi, ls.n) > 0.0f ? ls.n : -ls.n, ls.p_error)
                            : ls.p;
    shadow.tmax = glm::length(target - p);
  }
  return ShadowRay{shadow, medium_, width};
}

// The cone of a shadow ray from a vertex of footprint width towards a light sampled with solid-angle density pdf: like
// a sampled bounce's (geometry/ray_cone.h), a sample of density pdf among the pixel's paths stands for the solid angle
// 1/(paths pdf); towards a delta light every path's ray converges on one point, so the cone keeps the vertex's width.
RayCone Path::light_cone(float width, const Light& light, float pdf) const {
  return light.is_delta() ? RayCone{width, 0.0f} : cone_.scattered(width, pdf, paths_);
}

// A phase function's vertex where the current ray scattered in its medium, t along it.
bool Path::medium_vertex(float t, int depth) {
  if (emission_only_) return false;  // not a specular vertex
  const Vec3 p = ray_.o + t * ray_.d;
  const Vec3 wo = -ray_.d;
  const PhaseFunction* phase = medium_at(t).phase(p, arena_);
  const LightSampleContext ctx{p, Vec3(0.0f)};
  const Vec4 u_nee = sampler_.next_4d();   // light point (x, y), light choice (z), roulette (w)
  const Vec4 u_scat = sampler_.next_4d();  // phase direction (x, y)
  float light_pmf = 0.0f;
  const Light* light = choose_light(ctx, u_nee.z, &light_pmf);
  direct_lighting(
      ctx, u_nee, light, light_pmf,
      [&](const Vec3& wi, float* pdf) {
        const float f = phase->eval(wo, wi, rng());
        if (f > 0.0f) *pdf = phase->pdf(wo, wi);
        return f;
      },
      [&](const LightSample& ls) { return medium_shadow(p, cone_.width_at(t), ls); },
      light ? flight_weight(flight_, *light) : 1.0f);
  const PhaseSample ps = phase->sample(wo, Vec2(u_scat.x, u_scat.y), rng());
  if (features_ && !features_->set) {
    // The medium's own features, as a surface's: its single-scattering albedo, and the axis of its scatterers
    // (an SGGX fiber's tangent; zero for isotropic phase functions), so that the denoiser's weights tell a thread
    // from its neighbours. The axis at half length: within a pixel it varies along a thread's twisted plies, and
    // at full length the NL-means filter kept that as noise (docs/production.md: the demo's relMSE 11 % worse).
    const MediumProperties mp = medium_at(t).properties(p, ray_.d);
    Rgb albedo(0.0f);
    for (int c = 0; c < 3; ++c) albedo[c] = mp.sigma_t[c] > 0.0f ? mp.sigma_s[c] / mp.sigma_t[c] : 0.0f;
    set_features(albedo, kMediumAxisWeight * phase->feature_axis(), p);
  }
  if (!ps.valid()) return false;
  beta_ *= ps.weight();
  cone_ = cone_.scattered(cone_.width_at(t), ps.pdf, paths_);
  continue_path(Ray{p, ps.wi, kInfinity}, ps.pdf, false, ctx);
  prev_ltc_ = false;
  prev_shaping_ = ShapingQuery{};
  shaped_light_ = nullptr;
  return roulette(depth, u_nee.w);
}

// A BSDF's vertex at a ray hit; through a BSSRDF, a second one where the light leaves (path.h).
bool Path::surface_vertex(SurfaceInteraction& si, const Material& material, int depth) {
  material.perturb_shading(si);  // normal and bump maps: the shading frame the BSDF and the guard below use
  const Bsdf* bsdf = material.bsdf(si, arena_);
  const RgbProfile* profile = material.subsurface_profile(si, arena_);
  for (;;) {
    const Frame& frame = si.shading;
    const Vec3 wo_local = frame.to_local(si.wo);
    const float cos_o_geo = glm::dot(si.wo, si.ng);
    const uint32_t bsdf_flags = bsdf->flags();
    // Material surface occlusion: the equal-area cone at this point (Chan 2018 eq. 56), on wo's side.
    const SurfaceOcclusion* occlusion = material.surface_occlusion.get();
    const float cone_cos = occlusion ? occlusion->cone_cos(si) : 0.0f;
    const float side = wo_local.z >= 0.0f ? 1.0f : -1.0f;
    const bool guided = guidable(bsdf_flags, profile);
    const DirectionalQuadtree* guide = guided ? guiding_->distribution(si.p) : nullptr;

    // The context for light sampling: the normal on wo's side for reflection-only BSDFs (lets a
    // uniform environment sample the visible hemisphere), none when light may be transmitted.
    LightSampleContext ctx{si.p, Vec3(0.0f)};
    if (!(bsdf_flags & kBsdfTransmission)) ctx.n = wo_local.z >= 0.0f ? frame.n : -frame.n;

    // Two 4D points per vertex, drawn at every vertex so that dimensions line up: the 2D choices
    // (point on the light, BSDF direction) take Sobol dimensions 0 and 1, the best stratified pair.
    const Vec4 u_nee = sampler_.next_4d();   // light point (x, y), light choice (z), roulette (w)
    const Vec4 u_scat = sampler_.next_4d();  // BSDF direction (x, y), lobe (z)

    // "direct": "ltc", "ltc-ratio", "ltc-preview": polygon lights in closed form when the BSDF has LTC lobes. The
    // numbers of "ltc"'s visibility probes (x, y) are drawn where its control variate may be taken; those of
    // "ltc-ratio"'s and "ltc-preview"'s LTC sample (direction x, y; lobe z) at every surface vertex.
    float light_pmf = 0.0f;
    // Emission only: no light sampling (the numbers are still drawn, so later dimensions line up).
    const Light* light =
        has_non_delta(bsdf_flags) && !emission_only_ ? choose_light(ctx, u_nee.z, &light_pmf) : nullptr;
    const PolygonLight* polygon = light ? light->as_polygon() : nullptr;
    if (polygon && !polygon->analytic()) polygon = nullptr;
    std::array<LtcLobe, kMaxLtcLobes> lobes;
    int n_lobes = 0;
    Vec4 u_ltc(0.0f), u_probe(0.0f);
    // "ltc" only where the camera sees the vertex through specular vertices alone: deeper, the indirect light's
    // noise hides what it saves, and its probes and closed form made a sample up to twice as dear (docs/lights.md).
    // Nor where the pixel's neighbours found that it removed too little of their variance to pay for itself
    // (PixelMemory::learnt_skip).
    const bool ltc_pays = !memory_ || !memory_->learnt_skip;
    const bool may_have_lobes = direct_ != DirectLighting::Sample && has_non_delta(bsdf_flags) && !emission_only_ &&
                                (direct_ != DirectLighting::Ltc || (visible_ && ltc_pays));
    // "ltc": the light that would take the control variate at a vertex the camera sees, whichever light was chosen.
    const bool cv_vertex =
        direct_ == DirectLighting::Ltc && visible_ && ltc_pays && !emission_only_ && has_non_delta(bsdf_flags);
    const uint32_t cv_key = cv_vertex ? ltc_light(ctx) : 0;  // its name in the pixel's memory
    const PolygonLight* cv_light = cv_key ? ltc_lights_[cv_key - 1] : nullptr;
    const bool ltc_asked = cv_light && may_have_lobes;
    if (direct_ == DirectLighting::Ltc) {
      // Only where a control variate may be taken (some of the vertices the camera sees through specular ones; most
      // paths have one), not at every vertex of the path.
      if (cv_vertex) u_probe = sampler_.next_4d();
      if (ltc_asked) n_lobes = bsdf->ltc_lobes(wo_local, ltc_toward(si, wo_local, cv_light), lobes.data());
    } else if (direct_ != DirectLighting::Sample) {
      u_ltc = sampler_.next_4d();
      // The lobes exist or not whatever light was chosen (prev_ltc_ depends on it); `toward` only refines them.
      if (may_have_lobes) n_lobes = bsdf->ltc_lobes(wo_local, ltc_toward(si, wo_local, polygon), lobes.data());
    }
    // "ltc" (ltc_control_variate) adds to the sampled estimate below; the other two replace it.
    const bool closed_only = direct_ == DirectLighting::LtcRatio || direct_ == DirectLighting::LtcPreview;
    const std::span<const LtcLobe> ltc_lobes(lobes.data(), size_t(n_lobes));
    const bool control_variate = ltc_asked && n_lobes > 0;
    LightSample nee_sample;  // the light sample of the vertex's next-event estimate, for ltc_control_variate
    // "light_sampling": "lobe": a glossy lobe shapes the light samples of a flat area light.
    const ShapingQuery shaping = has_non_delta(bsdf_flags) && shapes_light_samples(bsdf_flags)
                                     ? ShapingQuery{bsdf, wo_local, frame, si.p}
                                     : ShapingQuery{};
    shaped_.reset();
    shaped_light_ = nullptr;
    if (shaping.bsdf && light && light->as_area()) {
      shaping.shape(*light->as_area(), &shaped_);
      shaped_light_ = light;
    }
    const LobeLightSampler* shaped = shaped_ && shaped_->valid() ? &*shaped_ : nullptr;
    // "ltc"'s coefficient from what the pixel's neighbours saw of this light (PixelMemory), where they saw it: then
    // no probes are traced. It depends on none of this sample's numbers, so the estimate stays unbiased.
    std::optional<float> learnt;
    if (control_variate && memory_ && memory_->learnt_light == cv_key) learnt = memory_->learnt_share;
    float nee_visibility = -1.0f;  // what the light sample's shadow ray saw (-1: none traced)
    if (polygon && n_lobes > 0 && closed_only) {
      const PathShadows shadows(*this, si, *polygon);
      const std::optional<Rgb> direct =
          ltc_direct(LtcVertex{si, *bsdf, wo_local, cos_o_geo}, ltc_lobes, *polygon, direct_, u_nee, u_ltc, shadows);
      if (direct) L_ += beta_ * *direct / light_pmf;
    } else if (light) {
      nee_sample = direct_lighting(
          ctx, u_nee, light, light_pmf,
          [&](const Vec3& wi, float* pdf) {
            const Vec3 wi_local = frame.to_local(wi);
            if (!sides_agree(cos_o_geo, si.ng, wi, wo_local, wi_local)) return Rgb(0.0f);
            const Rgb f = bsdf->eval_pdf(wo_local, wi_local, pdf);
            *pdf = mixture_pdf(guide, wi, *pdf);
            // Direct light through the bumps' cone (eq. 58); the density, and so the MIS weight, is unchanged.
            if (occlusion && wi_local.z * side > 0.0f) return f * occlusion->direct(cone_cos, wi_local.z * side);
            return f;
          },
          [&](const LightSample& ls) {
            return ShadowRay{ls.infinite ? si.spawn_ray(ls.wi) : si.spawn_ray_to(ls.p, ls.n, ls.p_error),
                             medium_after(si, ls.wi, medium_), si.cone_width};
          },
          1.0f, shaped, control_variate && light == cv_light ? &nee_visibility : nullptr);
    }

    const BsdfSample bs = guided ? guided_sample(*bsdf, frame, wo_local, u_scat, guide)
                                 : bsdf->sample(wo_local, u_scat.z, Vec2(u_scat.x, u_scat.y));
    if (control_variate) {
      const PathShadows shadows(*this, si, *cv_light);
      // The light's own sample, where it was the light chosen, and the sampler that drew (or would have drawn) its
      // points, for the densities of both directions.
      const LightSample cv_sample = light == cv_light ? nee_sample : LightSample{};
      std::optional<LobeLightSampler> cv_shaped_other;
      if (light != cv_light && shaping.bsdf) shaping.shape(*cv_light, &cv_shaped_other);
      const LobeLightSampler* cv_shaped =
          light == cv_light ? shaped : (cv_shaped_other && cv_shaped_other->valid() ? &*cv_shaped_other : nullptr);
      // The density the vertex's own sampling draws the light sample's direction with, as direct_lighting weighed it.
      const float ls_scatter_pdf =
          cv_sample.valid() ? mixture_pdf(guide, cv_sample.wi, bsdf->pdf(wo_local, frame.to_local(cv_sample.wi)))
                            : 0.0f;
      float cv_beta = learnt.value_or(0.0f);
      if (!learnt) {
        const LtcVisibility probes = ltc_probe_visibility(si, ltc_lobes, *cv_light, cv_shaped, ctx, u_probe, shadows);
        cv_beta = probes.share();
        if (memory_ && !memory_->light) memory_->light = cv_key;
        if (memory_ && memory_->light == cv_key) {
          memory_->seen += probes.seen;
          memory_->all += probes.all;
        }
      }
      // The light sample's shadow ray, traced anyway, teaches the neighbours' later samples.
      if (memory_ && memory_->light == cv_key && nee_visibility >= 0.0f) {
        const float g = ltc_visibility_weight(si, ltc_lobes, cv_sample);
        memory_->seen += g * nee_visibility;
        memory_->all += g;
      }
      // The probability that the light choice takes it (0 where it cannot: no control variate then).
      const float cv_pmf = light == cv_light ? light_pmf : Path::light_pmf(ctx, *cv_light);
      const Rgb cv = beta_ * ltc_control_variate(LtcVertex{si, *bsdf, wo_local, cos_o_geo}, ltc_lobes, *cv_light,
                                                 cv_pmf, cv_sample, ls_scatter_pdf, bs, cv_shaped, cv_beta);
      L_ += cv;
      cv_added_ += cv;
      cv_taken_ = true;
    }
    if (features_ && !features_->set) {
      // The sample's own weight, the path's first direction: an albedo estimate that costs no extra draw.
      const Rgb sw = bs.weight();
      const Rgb w = bs.valid() && is_finite(sw) ? sw : Rgb(0.0f);
      if (profile) {
        // A subsurface object's colour is its profile's albedo A (as Cycles' albedo pass reports it): the sample's
        // weight, of a reflection or a transmission through the boundary, is about 1 either way and tells neither
        // the colour nor the same value twice, and the filters kept the demo's jade pixels of the rarer value
        // apart from their neighbours, as speckles.
        set_features(profile->albedo(), wo_local.z >= 0.0f ? frame.n : -frame.n, si.p);
      } else if (bs.valid() && bs.delta() && feature_deltas_ < kFeatureDeltas && !is_black(w)) {
        if (feature_deltas_++ == 0) feature_p_ = si.p;
        feature_beta_ *= glm::min(w, Rgb(1.0f));
      } else {
        // Where the BSDF describes itself as LTC lobes, its directional albedo (Bsdf::ltc_albedo): a noise-free
        // feature, where one sample's weight varies with the lobe it chose (plastic's coat or base) and its direction.
        const std::optional<Rgb> albedo = bsdf->ltc_albedo(wo_local);
        set_features(albedo && is_finite(*albedo) ? *albedo : w, wo_local.z >= 0.0f ? frame.n : -frame.n, si.p);
      }
    }
    if (!bs.valid() || is_black(bs.f)) return false;
    if (emission_only_ && !bs.delta()) return false;

    if (profile && (bs.flags & kBsdfTransmission)) {
      visible_ = false;  // light leaving elsewhere through the BSSRDF is not seen through a specular chain
      if (emission_only_) return false;
      // Into the BSSRDF: the refracted direction is not followed; probe rays find where the light
      // leaves (bssrdf/probe_sampling.h), and the path goes on from there through the exit BSDF.
      ProbeSample ps;
      if (!sample_probe(scene_.accel(), si, *profile, sampler_.next_4d(), &ps, &counters_.probe_rays)) return false;
      beta_ *= bs.weight() * ps.weight;
      if (is_black(beta_)) return false;
      const float entry_width = si.cone_width;  // the exit point's footprint: the entry's, the best we know
      si = ps.si;
      si.cone_width = entry_width;
      si.wo = si.ng;  // light leaves on the front side; the exit BSDF ignores wo otherwise
      material.perturb_shading(si);
      bsdf = material.subsurface_exit_bsdf(si, arena_);
      profile = nullptr;
      continue;
    }

    const Vec3 wi = glm::normalize(frame.to_world(bs.wi));
    if (!sides_agree(cos_o_geo, si.ng, wi, wo_local, bs.wi)) return false;
    beta_ *= bs.f / bs.pdf;
    if (occlusion && bs.wi.z * side > 0.0f) {
      // The same factor as light sampling's on the emitter this ray may meet; the lobe's share of the cone on the
      // rest.
      occlusion_direct_ = occlusion->direct(cone_cos, bs.wi.z * side);
      occlusion_indirect_ = occlusion->indirect(cone_cos, wo_local.z * side, bs.wi.z * side, bs.flags);
    }
    if (bs.flags & kBsdfTransmission) eta_scale_ *= bs.eta * bs.eta;
    spread_cone(si, bs);
    medium_ = medium_after(si, wi, medium_);
    if (record_ && guided && n_recorded_ < kMaxRecordedVertices)
      recorded_[n_recorded_++] = RecordedVertex{si.p, wi, bs.pdf, beta_, L_};
    continue_path(si.spawn_ray(wi), bs.pdf, bs.delta(), ctx);
    prev_ltc_ = closed_only && n_lobes > 0;
    prev_shaping_ = shaping;
    return roulette(depth, u_nee.w);
  }
}

// Next-event estimation at the vertex ctx: the light choose_light took from u.z (with probability pmf; null: none),
// a point on it (u.x, u.y), its shadow transmittance, and the power heuristic against the vertex's own sampling.
// scatter(wi, &pdf) gives the vertex's value towards wi and the density it would sample wi with;
// shadow(ls) gives the shadow ray towards the light sample and the medium it starts in; weight scales the estimate (a
// free-flight vertex's MIS weight against equiangular sampling, flight_weight). Returns the light sample it drew
// (invalid where there was none), whatever its contribution.
template <class Scatter, class Shadow>
LightSample Path::direct_lighting(const LightSampleContext& ctx, const Vec4& u, const Light* light, float pmf,
                                  Scatter&& scatter, Shadow&& shadow, float weight, const LobeLightSampler* shaped,
                                  float* visibility) {
  if (!light) return LightSample{};
  const LightSample ls = shaped ? shaped->sample(ctx, Vec2(u.x, u.y)) : light->sample(ctx, Vec2(u.x, u.y));
  if (!ls.valid() || is_black(ls.radiance)) return ls;
  float scatter_pdf = 0.0f;
  const auto f = scatter(ls.wi, &scatter_pdf);
  if (no_contribution(f)) return ls;
  const ShadowRay s = shadow(ls);
  const Rgb T = shadow_transmittance(s.ray, s.medium, light_cone(s.width, *light, pmf * ls.pdf));
  if (visibility) *visibility = std::clamp(luminance(T), 0.0f, 1.0f);
  if (is_black(T)) return ls;
  const float light_pdf = pmf * ls.pdf;
  const float w = weight * (light->is_delta() ? 1.0f : power_heuristic(light_pdf, scatter_pdf));
  if constexpr (std::is_same_v<std::decay_t<decltype(f)>, float>)
    L_ += beta_ * T * ls.radiance * (f * w / light_pdf);  // a scalar value joins the scalar factor
  else
    L_ += beta_ * T * f * ls.radiance * (w / light_pdf);
  return ls;
}

// The light for next-event estimation at ctx (u) and its probability: by the light hierarchy, or in proportion to
// power ("light_selection": "power"); null when none can light ctx.
const Light* Path::choose_light(const LightSampleContext& ctx, float u, float* pmf) const {
  if (scene_.settings.light_tree) return scene_.light_tree().sample(ctx, u, pmf);
  const LightSampler& lights = scene_.light_sampler();
  return lights.empty() ? nullptr : lights.sample(u, pmf);
}

uint32_t Path::ltc_light(const LightSampleContext& ctx) const {
  if (ltc_lights_.empty()) return 0;
  if (memory_ && memory_->learnt_light >= 1 && memory_->learnt_light <= ltc_lights_.size())
    return memory_->learnt_light;
  if (ltc_lights_.size() == 1) return 1;
  uint32_t best = 0;
  float best_pmf = 0.0f;
  for (size_t i = 0; i < ltc_lights_.size(); ++i)
    if (const float p = light_pmf(ctx, *ltc_lights_[i]); p > best_pmf) best = uint32_t(i + 1), best_pmf = p;
  return best;
}

// The probability that choose_light(ctx, ·) takes light.
float Path::light_pmf(const LightSampleContext& ctx, const Light& light) const {
  return scene_.settings.light_tree ? scene_.light_tree().pmf(ctx, &light) : scene_.light_sampler().pmf(&light);
}

// Emission where the current ray met a light, weighted against light sampling unless the ray came from the
// camera or a delta lobe (which light sampling cannot produce).
void Path::emission(const Light& light, const LightHit& hit) {
  // After a vertex with LTC lobes in "ltc-ratio" or "ltc-preview" an analytic polygon light does not count ("ltc"
  // keeps the usual weights: its control variate mirrors them).
  const PolygonLight* polygon = light.as_polygon();
  if (prev_ltc_ && !specular_bounce_ && polygon && polygon->analytic()) return;
  if (specular_bounce_) {
    const Rgb Le = light.eval(hit) * occlusion_direct_;  // surface occlusion of the vertex the ray left (1: none)
    L_ += beta_ * Le;
    if (visible_ && features_) features_->emission += beta_ * Le;
    return;
  }
  // The radiance and light sampling's density together (an environment maps the direction once for both).
  float pdf = 0.0f;
  const Rgb Le = light.eval_pdf(prev_ctx_, hit, &pdf) * occlusion_direct_;
  if (is_black(Le)) return;
  const float light_pdf = light_pmf(prev_ctx_, light) * shaped_light_pdf(light, hit.wi, pdf);
  L_ += beta_ * Le * (power_heuristic(prev_pdf_, light_pdf) * flight_weight(prev_flight_, light));
}

float Path::shaped_light_pdf(const Light& light, const Vec3& wi, float light_pdf) const {
  const DiffuseAreaLight* area = light.as_area();
  if (!prev_shaping_.bsdf || !area || !(light_pdf > 0.0f)) return light_pdf;
  std::optional<LobeLightSampler> other;
  const std::optional<LobeLightSampler>& shaped = &light == shaped_light_ ? shaped_ : other;
  if (&light != shaped_light_) prev_shaping_.shape(*area, &other);
  return shaped && shaped->valid() ? shaped->pdf(wi, light_pdf) : light_pdf;
}

void Path::continue_path(const Ray& ray, float pdf, bool specular, const LightSampleContext& ctx) {
  ray_ = ray;
  prev_pdf_ = pdf;
  prev_flight_ = flight_;
  flight_.active = false;
  specular_bounce_ = specular;
  visible_ = visible_ && specular;
  prev_ctx_ = ctx;
}

// The cone leaving si along bs (geometry/ray_cone.h): a delta lobe bends it by the surface's curvature, a sampled
// lobe widens it by the direction's share of the lobe.
void Path::spread_cone(const SurfaceInteraction& si, const BsdfSample& bs) {
  if (!bs.delta()) {
    cone_ = cone_.scattered(si.cone_width, bs.pdf, paths_);
    return;
  }
  const float k = surface_curvature(si);
  const float kappa = si.front_face ? k : -k;  // seen from the side the ray arrived on
  cone_ = (bs.flags & kBsdfTransmission) ? cone_.refracted(si.cone_width, kappa, bs.eta)
                                         : cone_.reflected(si.cone_width, kappa);
}

// Russian roulette after kRouletteDepth bounces (path.h); false ends the path.
bool Path::roulette(int depth, float u) {
  if (depth >= kRouletteDepth) {
    // sqrt (path.h): on the Cornell box 10 % less variance for the same time, on the lit medium box of
    // bench/cycles 9 %.
    const float survive = std::min(1.0f, std::sqrt(max_component(beta_) * eta_scale_));
    if (u >= survive) return false;
    beta_ /= survive;
  }
  return !is_black(beta_);
}

// Transmittance of a shadow ray: plain occlusion in a scene without media; with media, through index-matched
// boundaries (any surface with a material, and any emitter, blocks), in closed form in homogeneous media and by ratio
// tracking in the others.
Rgb Path::shadow_transmittance(Ray ray, const Medium* medium, RayCone cone) {
  if (!scene_.has_media()) {
    ++counters_.shadow_rays;
    return scene_.occluded(ray) ? Rgb(0.0f) : Rgb(1.0f);
  }
  Rgb T(1.0f);
  // The ray's end, where every continuation past a boundary re-aims: shortening tmax by the distance to the offset
  // origin instead overshoots by up to the offset's share across the ray, enough to reach the light behind the target
  // at grazing angles (measured: half of the light sampled from a medium 0.2 below a large quad light was lost;
  // tests/integrators/test_path_analytic.cpp SquareAreaLightThroughMediumBoundaries).
  const bool finite = std::isfinite(ray.tmax);
  const Vec3 end = finite ? ray.o + ray.tmax * ray.d : Vec3(0.0f);
  for (int crossing = 0; crossing < kMaxNullCrossings; ++crossing) {
    SurfaceInteraction si;
    ++counters_.shadow_rays;
    const bool hit = scene_.intersect(ray, si);
    const float t_end = hit ? si.t : ray.tmax;
    if (const MediumProperties* h = medium ? medium->homogeneous() : nullptr)
      T *= homogeneous_transmittance(h->sigma_t, t_end);
    else if (medium)
      T *= ratio_tracking(*medium, ray, t_end, rng(), budget_, cone);
    if (!hit) return T;
    if (si.shape->material || !si.shape->has_medium_interface() || si.shape->light(si.prim)) return Rgb(0.0f);
    if (is_black(T)) return T;
    medium = medium_after(si, ray.d, medium);
    cone.width = cone.width_at(si.t);  // the cone goes on through the boundary
    const Vec3 o = si.spawn_origin(ray.d);
    if (!finite) {
      ray.o = o;
      continue;
    }
    const Vec3 to_end = end - o;
    const float length = glm::length(to_end);
    if (!(length > 0.0f) || glm::dot(to_end, ray.d) <= 0.0f) return T;  // the boundary lies at the end itself
    ray = Ray{o, to_end / length, length};
  }
  return Rgb(0.0f);
}

// Free-flight sampling, ratio tracking and stochastic phase functions draw an unbounded number of random
// numbers: a generator seeded from the sampler when the path first needs it.
Pcg32& Path::rng() {
  if (!rng_seeded_) {
    const Vec4 u = sampler_.next_4d();
    rng_.seed(mix64((uint64_t(u.x * 4294967296.0f) << 32) ^ uint64_t(u.y * 4294967296.0f)),
              mix64((uint64_t(u.z * 4294967296.0f) << 32) ^ uint64_t(u.w * 4294967296.0f)));
    rng_seeded_ = true;
  }
  return rng_;
}

}  // namespace

PathIntegrator::PathIntegrator(const Scene& scene, int max_depth, DirectLighting direct)
    : scene_(scene), max_depth_(max_depth), direct_(direct) {
  if (direct_ != DirectLighting::Ltc) return;
  for (const std::unique_ptr<Light>& light : scene_.lights)
    if (const PolygonLight* polygon = light->as_polygon();
        polygon && polygon->analytic() && !polygon->textured() && average(polygon->power()) > 0.0f)
      ltc_lights_.push_back(polygon);
  // The brightest first (ties in scene order), so that the set depends on the scene alone.
  std::stable_sort(ltc_lights_.begin(), ltc_lights_.end(), [](const PolygonLight* a, const PolygonLight* b) {
    return average(a->power()) > average(b->power());
  });
  if (ltc_lights_.size() > kMaxLtcLights) ltc_lights_.resize(kMaxLtcLights);
  // No light to take the control variate: "ltc" is "sample", to the random number (no pixel memory, no probes' numbers
  // drawn), so that a scene without polygon lights costs nothing in this mode.
  if (ltc_lights_.empty()) direct_ = DirectLighting::Sample;
}

Rgb PathIntegrator::li(const Ray& camera_ray, Sampler& sampler, Arena& arena, RayCounters& counters,
                       const StopFlag& stop) const {
  return li_pixel(camera_ray, sampler, arena, counters, stop, nullptr, nullptr);
}

Rgb PathIntegrator::li_features(const Ray& camera_ray, Sampler& sampler, Arena& arena, RayCounters& counters,
                                const StopFlag& stop, PixelFeatures& features) const {
  return li_pixel(camera_ray, sampler, arena, counters, stop, &features, nullptr);
}

Rgb PathIntegrator::li_pixel(const Ray& camera_ray, Sampler& sampler, Arena& arena, RayCounters& counters,
                             const StopFlag& stop, PixelFeatures* features, PixelMemory* memory) const {
  Path path(scene_, camera_ray, sampler, arena, counters, stop, direct_, guiding_, record_);
  if (features) {
    *features = PixelFeatures{};
    path.record_features(features);
  }
  path.use_memory(memory);
  path.use_ltc_lights(ltc_lights_);
  const Rgb L = path.trace(max_depth_);
  if (memory && is_finite(L)) {
    const float l = luminance(L);
    memory->samples += 1.0f;
    memory->sum += l;
    memory->sum2 += l * l;
    if (path.cv_taken()) {
      const float without = luminance(L - path.cv_added());
      memory->cv_samples += 1.0f;
      memory->with_sum += l;
      memory->with_sum2 += l * l;
      memory->without_sum += without;
      memory->without_sum2 += without * without;
    }
  }
  return L;
}

Rgb PathIntegrator::visible_emission(const Ray& camera_ray, Sampler& sampler, Arena& arena, RayCounters& counters,
                                     const StopFlag& stop) const {
  Path path(scene_, camera_ray, sampler, arena, counters, stop, direct_, guiding_);
  path.visible_emission_only();
  // Only emission through specular vertices reaches L: every other contribution needs a vertex that is not.
  return path.trace(max_depth_);
}

}  // namespace kozu
