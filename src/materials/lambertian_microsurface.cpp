// The Lambertian-facet microsurface walk: see lambertian_microsurface.h for the model and the equation map.
#include "materials/lambertian_microsurface.h"

#include "core/frame.h"
#include "core/warp.h"

#include <cmath>
#include <limits>

namespace kozu {

namespace {

// Free-path sampling in height as microsurface_walk's Walker::next_height (walk eqs. (2)–(4)), on the
// uniform-height microsurface (walk eq. (1), c = C1(h)): whether the ray leaving c along w meets a facet
// again, and where.
bool next_height(const MicrofacetDistribution& d, const Vec3& w, double* c, Pcg32& rng) {
  if (w.z == 0.0f) return true;  // a horizontal ray meets a facet where it is
  if (w.z < 0.0f) {
    const double lambda = 1.0 + d.lambda(w);   // |Λ| of a downward ray, walk eq. (2)
    const double u = 1.0 - rng.next_double();  // (0, 1]
    *c = std::max(*c * std::exp(std::log(u) / lambda), std::numeric_limits<double>::min());  // walk eq. (4)
    return true;
  }
  const double lambda = d.lambda(w);
  if (!(lambda > 0.0)) return false;
  const double u = 1.0 - rng.next_double();
  const double next = *c * std::exp(-std::log(u) / lambda);  // C1 = c u^(−1/Λ), walk eq. (4)
  if (next >= 1.0) return false;                             // above the highest point: it left
  *c = next;
  return true;
}

// Probability that a ray leaving height c along w (w.z > 0) escapes, G1(w, h) = C1(h)^Λ(w), walk eq. (3).
double escape(const MicrofacetDistribution& d, const Vec3& w, double c) {
  if (!(w.z > 0.0f)) return 0.0;
  return std::pow(c, static_cast<double>(d.lambda(w)));
}

}  // namespace

double LambertianMicrosurface::fresnel_weight(double am, double bm) const {
  if (!p_.diffuse_fresnel) return 1.0;
  const auto p5 = [](double x) {
    const double y = 1.0 - std::clamp(x, 0.0, 1.0);
    const double y2 = y * y;
    return y2 * y2 * y;
  };
  return 21.0 / 20.0 * (1.0 - p_.f0) * (1.0 - p5(am)) * (1.0 - p5(bm));  // Chan 2018 eqs. (61), (62), times π
}

double LambertianMicrosurface::eval(const Vec3& wo, const Vec3& wi, Pcg32& rng, int* order) const {
  if (order) *order = 0;
  if (!(wo.z > 0.0f) || !(wi.z > 0.0f)) return 0.0;
  Vec3 w = -wo;    // the ray travels along w
  double c = 1.0;  // from above the highest point of the microsurface
  double throughput = 1.0, sum = 0.0;
  for (int k = 0; k < kMaxOrder; ++k) {
    if (!next_height(d_, w, &c, rng)) break;  // it left the microsurface
    if (order) *order = k + 1;
    const Vec3 a = -w;
    // A visible normal from a, walk eq. (6); its Lambertian facet scatters towards wi (next event) and onwards.
    const Vec3 m = d_.sample_visible(a, Vec2(rng.next_float(), rng.next_float()));
    const double am = glm::dot(a, m);
    if (!(am > 0.0)) break;  // degenerate sample (a at the horizon of every facet): the walk ends
    const double im = glm::dot(wi, m);
    if (im > 0.0)
      sum += throughput * p_.albedo * fresnel_weight(am, im) * im * kInvPi * escape(d_, wi, c);  // NEE, walk eq. (10)
    const Vec3 b = Frame(m).to_world(warp::square_to_cosine_hemisphere(Vec2(rng.next_float(), rng.next_float())));
    throughput *= p_.albedo * fresnel_weight(am, glm::dot(b, m));
    if (!(throughput > 0.0)) break;
    w = glm::normalize(b);
  }
  return std::isfinite(sum) ? sum : 0.0;
}

double LambertianMicrosurface::eval_mean(const Vec3& wo, const Vec3& wi, int n, Pcg32& rng, double* std_error) const {
  double s = 0.0, s2 = 0.0;
  for (int i = 0; i < n; ++i) {
    const double x = eval(wo, wi, rng);
    s += x;
    s2 += x * x;
  }
  const double mean = n > 0 ? s / n : 0.0;
  const double cos_i = wi.z > 0.0f ? wi.z : 1.0;
  if (std_error) *std_error = n > 1 ? std::sqrt(std::max(s2 / n - mean * mean, 0.0) / (n - 1)) / cos_i : 0.0;
  return mean / cos_i;
}

void LambertianMicrosurface::slice_directions(double theta_h, double theta_d, Vec3* l, Vec3* v) {
  // The half vector at φ_h = 0 and the difference vector at φ_d = 90°, rotated by θ_h about y (Chan 2018 §5.6,
  // after Burley 2012's slice): both directions share z = cos θ_d cos θ_h.
  const double x = std::cos(theta_d) * std::sin(theta_h), y = std::sin(theta_d),
               z = std::cos(theta_d) * std::cos(theta_h);
  *l = Vec3(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
  *v = Vec3(static_cast<float>(x), static_cast<float>(-y), static_cast<float>(z));
}

}  // namespace kozu
