// The microsurface random walk of Heitz et al. 2016: see microsurface_walk.h for the model, the equation
// map (the "eq. (N)" tags below) and the estimators.
#include "materials/microsurface_walk.h"

#include <cstring>

#include "materials/fresnel.h"

#include <type_traits>

namespace kozu {

namespace {

// State of a walk: the ray travels along w, expressed in the frame of its side of the interface (side = +1
// outside, −1 inside, where z is flipped, eq. (9)), and sits at c = C1(h) of that frame.
//
// One walker per call: kConductor selects the conductor (reflection only, RGB Fresnel weight per bounce)
// or the dielectric (reflection or refraction chosen by the Fresnel reflectance, weight 1).
template <bool kConductor>
class Walker {
 public:
  using Spectrum = std::conditional_t<kConductor, Rgb, float>;

  Walker(const MicrofacetDistribution& d, const ConductorFresnel* fresnel, float eta, int max_order)
      : d_(d), fresnel_(fresnel), eta_(eta), max_order_(max_order) {}

  // Closed-form single scattering, eq. (11): the walk density p(wi | wo) restricted to one bounce.
  Spectrum single(const Vec3& wo, const Vec3& wi) const {
    const int side = wo.z > 0.0f ? 1 : -1;
    const Vec3 a(wo.x, wo.y, std::abs(wo.z));
    const Vec3 t(wi.x, wi.y, side * wi.z);
    const float lambda_a = d_.lambda(a), lambda_t = d_.lambda(t);
    if (t.z > 0.0f) {
      const Vec3 m = glm::normalize(a + t);
      const float am = glm::dot(a, m);
      if (!(am > 0.0f) || !(m.z > 0.0f)) return Spectrum(0.0f);
      const float value = d_.D(m) / (4.0f * a.z * (1.0f + lambda_a + lambda_t));  // eq. (11)
      if (!std::isfinite(value)) return Spectrum(0.0f);
      return reflectance(am, side) * value;
    }
    if constexpr (kConductor) {
      return Spectrum(0.0f);
    } else {
      const float eta = eta_local(side);
      Vec3 m;
      float am, tm, denom;
      if (!refraction_half_vector(a, t, eta, &m, &am, &tm, &denom)) return 0.0f;
      // Height-correlated transmission masking for the two sides of a uniform-height surface: the first
      // height has density (1 + Λa) c^Λa, the exit below has probability (1 − c)^Λt, so E = (1 + Λa) B.
      const double beta =
          std::exp(std::lgamma(1.0 + lambda_a) + std::lgamma(1.0 + lambda_t) - std::lgamma(2.0 + lambda_a + lambda_t));
      const double value = (1.0 - fresnel_dielectric(am, eta)) * d_.D(m) * am * std::abs(tm) * eta * eta * beta /
                           (a.z * static_cast<double>(denom) * denom);  // eq. (11)
      return std::isfinite(value) ? static_cast<float>(value) : 0.0f;
    }
  }

  // Samples the walk started along −wo; returns false if it is still on the microsurface after
  // max_order_ scattering events (counted as absorbed).
  bool sample(const Vec3& wo, Pcg32& rng, Vec3* wi, Spectrum* weight, int* order) const {
    int side = wo.z > 0.0f ? 1 : -1;
    Vec3 w(-wo.x, -wo.y, -std::abs(wo.z));
    double c = 1.0;  // the ray comes from above the highest point of the microsurface
    Spectrum throughput(1.0f);
    for (int k = 0;; ++k) {
      const Flight f = next_height(w, c, rng);
      if (!f.hit) {
        *wi = Vec3(w.x, w.y, side * w.z);
        *weight = throughput;
        if (order) *order = k;
        return true;
      }
      if (k == max_order_) {
        if (order) *order = k + 1;
        return false;
      }
      c = f.c;
      scatter(&side, &c, &w, &throughput, rng);
    }
  }

  // Next-event estimates of the walk started along −start towards the exit direction `target`, summed
  // over the vertices k >= 2 (order 1 is single(), in closed form), eq. (10). With mis, each term is
  // weighted against the reverse walk by the balance heuristic of eq. (12); r converts the reverse walk's
  // density into this walk's (p_this = r p_reverse, both at the same path).
  //
  // The next-event estimate for vertex k is made from vertex k − 1 with a forced intersection, eq. (13):
  // P(the ray meets a facet) times the estimate at a height drawn given that it does. An upward ray meets
  // a facet with a probability ∝ Λ that vanishes near the vertical, and then sees the few facets facing it
  // with D_ω ∝ 1/A(ω) ∝ 1/Λ: the plain estimate has infinite variance, the forced one is bounded.
  Spectrum walk_next_event(const Vec3& start, const Vec3& target, double r, bool mis, Pcg32& rng) const {
    int side = start.z > 0.0f ? 1 : -1;
    Vec3 w(-start.x, -start.y, -std::abs(start.z));
    double c = 1.0;
    Spectrum throughput(1.0f), sum(0.0f);
    if (max_order_ < 2) return sum;
    c = next_height(w, c, rng).c;  // vertex 1: a downward ray always meets the microsurface
    scatter(&side, &c, &w, &throughput, rng);
    // The reverse walk ends at vertex 1: it arrives along −d1 and connects to start. Its estimate is
    // reverse_base times its own forced-intersection probability for the segment from vertex 2.
    const Vec3 d1 = w;
    const double reverse_base = mis ? next_event(side, c, d1, start, nullptr) : 0.0;
    double c2 = 0.0;  // height of vertex 2 in the frame of d1's side
    for (int k = 1; k < max_order_; ++k) {
      // k scattering events so far; the ray leaves height c along w. Estimate vertex k + 1.
      const Flight f = next_height(w, c, rng);
      if (f.hit_probability > 0.0) {
        Spectrum fresnel(1.0f);
        const double nee = f.hit_probability * next_event(side, f.forced_c, -w, target, &fresnel);
        if (nee > 0.0) {
          double weight = 1.0;
          if (mis) {
            const double c_v2 = k == 1 ? f.forced_c : c2;
            const double reverse = reverse_base * hit_probability(-d1, c_v2);
            weight = r * reverse / (nee + r * reverse);  // eq. (12)
          }
          sum += throughput * fresnel * static_cast<float>(nee * weight);
        }
      }
      if (!f.hit) break;
      c = f.c;
      if (k == 1) c2 = c;
      if (k + 1 == max_order_) break;
      scatter(&side, &c, &w, &throughput, rng);
    }
    return sum;
  }

 private:
  float eta_local(int side) const { return side > 0 ? eta_ : 1.0f / eta_; }

  // Conductor: the RGB Fresnel term; dielectric: the reflectance, the probability of reflecting.
  Spectrum reflectance(float cos_am, int side) const {
    if constexpr (kConductor) {
      (void)side;
      return fresnel_->eval(cos_am);
    } else {
      return fresnel_dielectric(cos_am, eta_local(side));
    }
  }

  // |cos θ| Λ(ω) for ω of either hemisphere, finite at the horizon (where Λ is infinite).
  float cos_lambda(const Vec3& w) const {
    const float c = std::abs(w.z);
    const float s2 = sqr(d_.alpha_x() * w.x) + sqr(d_.alpha_y() * w.y);  // α(φ)² sin²θ
    if (s2 <= 0.0f) return 0.0f;
    if (d_.type() == MicrofacetType::GGX) return s2 / (2.0f * (std::sqrt(c * c + s2) + c));
    const float s = std::sqrt(s2);
    const float a = c / s;
    if (a >= 4.5f) return 0.0f;  // as MicrofacetDistribution::lambda: below float resolution
    return 0.5f * (s * std::exp(-a * a) / std::sqrt(kPi) - c * std::erfc(a));
  }

  // Projected area of the microsurface seen from w, eq. (5).
  float projected_area(const Vec3& w) const { return std::max(w.z, 0.0f) + cos_lambda(w); }

  // Density of the normals visible from w (either hemisphere), eq. (6).
  double d_visible(const Vec3& w, const Vec3& m) const {
    const float wm = glm::dot(w, m);
    if (!(wm > 0.0f)) return 0.0;
    const double area = projected_area(w);
    return area > 0.0 ? wm * static_cast<double>(d_.D(m)) / area : 0.0;
  }

  // Free-path sampling in height, eq. (4): whether the ray leaving height c along w meets a facet, and
  // where (c); also P(hit) and a height drawn given a hit (the same one when the ray did hit), eq. (13).
  struct Flight {
    bool hit;
    double c;                // where it met the facet (when hit)
    double hit_probability;  // 1 − G1(w, h) for upward rays, 1 for downward ones
    double forced_c;         // a height distributed as the intersection given that there is one
  };
  Flight next_height(const Vec3& w, double c, Pcg32& rng) const {
    if (w.z == 0.0f) return {true, c, 1.0, c};  // a horizontal ray meets a facet where it is
    if (w.z < 0.0f) {
      // Downward rays always meet a facet: at C1 = c u^(1/|Λ|), eq. (4), with |Λ| of eq. (2).
      const double lambda = 1.0 + d_.lambda(w);
      const double u = 1.0 - rng.next_double();  // (0, 1]
      const double next = std::max(c * std::exp(std::log(u) / lambda), std::numeric_limits<double>::min());
      return {true, next, 1.0, next};
    }
    const double lambda = d_.lambda(w);
    if (!(lambda > 0.0)) return {false, c, 0.0, c};  // nothing masks: it leaves
    // It leaves with probability G1(w, h) = C1(h)^Λ, eq. (3). With v uniform, it meets a facet iff
    // v < 1 − C1(h)^Λ, then at C1 = c (1 − v)^(−1/Λ), eq. (4); a forced intersection redraws v below it.
    const double hit_probability = -std::expm1(lambda * std::log(c));
    const double v = rng.next_double();
    const bool hit = v < hit_probability;
    const double v_hit = hit ? v : hit_probability * rng.next_double();
    const double next = std::min(c * std::exp(-std::log1p(-v_hit) / lambda), 1.0);
    return {hit, next, hit_probability, next};
  }

  // Probability that a ray leaving height c along w meets a facet, eqs. (3), (4).
  double hit_probability(const Vec3& w, double c) const {
    if (!(w.z > 0.0f)) return 1.0;
    return -std::expm1(static_cast<double>(d_.lambda(w)) * std::log(c));
  }

  // Probability that a ray leaving height c (its side's frame) in direction w escapes, eq. (3).
  double escape(const Vec3& w, double c) const {
    if (!(w.z > 0.0f)) return 0.0;
    return std::pow(c, static_cast<double>(d_.lambda(w)));
  }

  // The refraction half vector of eq. (8), oriented to m.z > 0, with the dot products and the Jacobian's
  // denominator am + eta tm; false unless a and t lie on opposite sides of a proper facet.
  static bool refraction_half_vector(const Vec3& a, const Vec3& t, float eta, Vec3* m, float* am, float* tm,
                                     float* denom) {
    Vec3 h = -(a + eta * t);
    const float len = glm::length(h);
    if (!(len > 0.0f)) return false;
    h /= len;
    if (h.z < 0.0f) h = -h;
    *am = glm::dot(a, h);
    *tm = glm::dot(t, h);
    *denom = *am + eta * *tm;
    *m = h;
    return h.z > 0.0f && *am > 0.0f && *tm < 0.0f && *denom != 0.0f;
  }

  // Next-event estimation: density that a facet met by a ray arriving along −a (side frame `side`,
  // height c) scatters towards the global direction `target` and that the ray then leaves the
  // microsurface, eqs. (7), (8), (3). The conductor's Fresnel factor goes to *fresnel, apart from the
  // density, so that MIS weights use the Fresnel-free densities the sampler draws with.
  double next_event(int side, double c, const Vec3& a, const Vec3& target, Spectrum* fresnel) const {
    const Vec3 t(target.x, target.y, side * target.z);
    if (t.z > 0.0f) {
      Vec3 m = a + t;
      const float len = glm::length(m);
      if (!(len > 0.0f)) return 0.0;
      m /= len;
      const float am = glm::dot(a, m);
      if (!(am > 0.0f) || !(m.z > 0.0f)) return 0.0;
      double density = d_visible(a, m) / (4.0 * am);  // eq. (7)
      if constexpr (kConductor) {
        if (fresnel) *fresnel = reflectance(am, side);
      } else {
        density *= reflectance(am, side);  // eq. (8), reflection
      }
      const double value = density * escape(t, c);
      return std::isfinite(value) ? value : 0.0;
    }
    if constexpr (kConductor) {
      return 0.0;
    } else {
      const float eta = eta_local(side);
      Vec3 m;
      float am, tm, denom;
      if (!refraction_half_vector(a, t, eta, &m, &am, &tm, &denom)) return 0.0;
      const double density = (1.0 - fresnel_dielectric(am, eta)) * d_visible(a, m) * eta * eta * std::abs(tm) /
                             (static_cast<double>(denom) * denom);           // eq. (8), refraction
      const double value = density * escape(Vec3(t.x, t.y, -t.z), 1.0 - c);  // eq. (9), (3) on the far side
      return std::isfinite(value) ? value : 0.0;
    }
  }

  // Samples the phase function at the facet met by the ray travelling along *w: a visible normal from
  // −w, eq. (6), then reflection (conductor: weight F) or Fresnel's choice of reflection or refraction
  // (dielectric, eq. (8)); a refraction crosses to the other side, eq. (9).
  void scatter(int* side, double* c, Vec3* w, Spectrum* throughput, Pcg32& rng) const {
    const Vec3 a = -*w;
    const float u0 = rng.next_float(), u1 = rng.next_float();
    const Vec3 m = d_.sample_visible(a, Vec2(u0, u1));
    const float am = glm::dot(a, m);
    Vec3 next = reflect(a, m);
    if constexpr (kConductor) {
      *throughput *= reflectance(std::max(am, 0.0f), *side);  // eq. (7): the sampler draws D_ω, F is the weight
    } else {
      (void)throughput;
      // am <= 0 only by rounding at grazing incidence, where F -> 1: reflect.
      const float eta = eta_local(*side);
      const float reflect_probability = am > 0.0f ? fresnel_dielectric(am, eta) : 1.0f;
      Vec3 refracted;
      if (rng.next_float() >= reflect_probability && refract(a, m, eta, &refracted)) {
        *side = -*side;
        next = Vec3(refracted.x, refracted.y, -refracted.z);
        *c = 1.0 - *c;
      }
    }
    *w = glm::normalize(next);
  }

  const MicrofacetDistribution& d_;
  const ConductorFresnel* fresnel_;
  float eta_;
  int max_order_;
};

}  // namespace

Rgb MicrosurfaceWalk::eval_conductor(const Vec3& wo, const Vec3& wi, const ConductorFresnel& F, Pcg32& rng) const {
  Vec3 o = wo, i = wi;
  if (o.z < 0.0f) {  // two-sided: mirror to the upper side
    o.z = -o.z;
    i.z = -i.z;
  }
  if (!(o.z > 0.0f) || !(i.z > 0.0f)) return Rgb(0.0f);
  const Walker<true> walker(d_, &F, 1.0f, max_order_);
  Rgb value = walker.single(o, i);
  if (max_order_ == 1) return value;
  if (!bidirectional_) return value + walker.walk_next_event(o, i, 0.0, false, rng);
  const double r = static_cast<double>(i.z) / o.z;  // eq. (12): p(wi | wo) = r p(wo | wi)
  value += walker.walk_next_event(o, i, r, true, rng);
  value += static_cast<float>(r) * walker.walk_next_event(i, o, 1.0 / r, true, rng);
  return value;
}

bool MicrosurfaceWalk::sample_conductor(const Vec3& wo, const ConductorFresnel& F, Pcg32& rng, Vec3* wi, Rgb* weight,
                                        int* order) const {
  const bool flip = wo.z < 0.0f;
  const Vec3 o(wo.x, wo.y, std::abs(wo.z));
  if (!(o.z > 0.0f)) return false;
  const Walker<true> walker(d_, &F, 1.0f, max_order_);
  if (!walker.sample(o, rng, wi, weight, order)) return false;
  if (flip) wi->z = -wi->z;
  return true;
}

float MicrosurfaceWalk::eval_dielectric(const Vec3& wo, const Vec3& wi, float eta, TransportMode mode,
                                        Pcg32& rng) const {
  if (wo.z == 0.0f || wi.z == 0.0f) return 0.0f;
  const Walker<false> walker(d_, nullptr, eta, max_order_);
  const bool transmission = (wo.z > 0.0f) != (wi.z > 0.0f);
  // IOR on wi's side over IOR on wo's side (bsdf.h's eta).
  const float eta_io = transmission ? (wi.z < 0.0f ? eta : 1.0f / eta) : 1.0f;
  double value = walker.single(wo, wi);
  if (max_order_ > 1) {
    if (!bidirectional_) {
      value += walker.walk_next_event(wo, wi, 0.0, false, rng);
    } else {
      // eq. (12), generalised reciprocity: p(wi | wo) = |cos θi| / |cos θo| · eta_io² · p(wo | wi).
      const double r = std::abs(static_cast<double>(wi.z) / wo.z) * eta_io * eta_io;
      value += walker.walk_next_event(wo, wi, r, true, rng);
      value += r * walker.walk_next_event(wi, wo, 1.0 / r, true, rng);
    }
  }
  // The walk transports importance; radiance through the interface scales by 1/eta_io² (bsdf.h).
  if (mode == TransportMode::Radiance && transmission) value /= static_cast<double>(eta_io) * eta_io;
  return static_cast<float>(value);
}

bool MicrosurfaceWalk::sample_dielectric(const Vec3& wo, float eta, TransportMode mode, Pcg32& rng, Vec3* wi,
                                         float* weight, int* order) const {
  if (wo.z == 0.0f) return false;
  const Walker<false> walker(d_, nullptr, eta, max_order_);
  float throughput;
  if (!walker.sample(wo, rng, wi, &throughput, order)) return false;
  *weight = 1.0f;
  if (mode == TransportMode::Radiance && (wo.z > 0.0f) != (wi->z > 0.0f)) {
    const float eta_io = wi->z < 0.0f ? eta : 1.0f / eta;
    *weight = 1.0f / (eta_io * eta_io);
  }
  return true;
}

Pcg32 walk_rng(const Vec3& a, const Vec3& b, uint64_t salt) {
  uint32_t bits[6];
  std::memcpy(bits, &a, sizeof(Vec3));
  std::memcpy(bits + 3, &b, sizeof(Vec3));
  uint64_t h = salt;
  for (const uint32_t v : bits) h = mix64(h ^ v);
  return Pcg32(h, mix64(h));
}

}  // namespace kozu
