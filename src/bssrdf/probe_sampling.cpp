#include "bssrdf/probe_sampling.h"

#include "core/frame.h"
#include "geometry/embree_scene.h"

#include <cmath>

namespace kozu {

namespace {
constexpr float kAxisProb[3] = {0.25f, 0.25f, 0.5f};  // tangent s, tangent t, normal
constexpr float kChannelProb = 1.0f / 3.0f;
}  // namespace

RgbProfile::RgbProfile(const std::array<NormalizedDiffusion, 3>& channels) : ch_(channels) {
  for (int c = 0; c < 3; ++c) r_max_[c] = ch_[c].radius_of_fraction(kProbeFraction);
}

Rgb RgbProfile::eval(float r) const { return Rgb(ch_[0].eval(r), ch_[1].eval(r), ch_[2].eval(r)); }

float RgbProfile::pdf_radius(int c, float r) const {
  if (r > r_max_[c]) return 0.0f;
  return ch_[c].pdf(r) / kProbeFraction;
}

float RgbProfile::sample_radius(int c, float u) const { return std::min(ch_[c].sample(u * kProbeFraction), r_max_[c]); }

float probe_pdf(const Vec3& xo, const Vec3& no, const Vec3& xi, const Vec3& ni, const RgbProfile& profile) {
  const Frame f(no);
  const Vec3 d = xi - xo;
  const float dist2 = glm::dot(d, d);
  const Vec3 dl = f.to_local(d), nl = f.to_local(ni);
  float sum = 0.0f;
  for (int a = 0; a < 3; ++a) {
    // From the two other components: dist² − along² cancels for points far along the axis.
    const float r = std::sqrt(dl[(a + 1) % 3] * dl[(a + 1) % 3] + dl[(a + 2) % 3] * dl[(a + 2) % 3]);
    if (!(r > 0.0f)) continue;  // xi on the axis through xo: a set of zero area
    const float cos_a = std::abs(nl[a]);
    for (int c = 0; c < 3; ++c) {
      if (dist2 > profile.r_max(c) * profile.r_max(c)) continue;
      sum += kAxisProb[a] * kChannelProb * profile.pdf_radius(c, r) / (kTwoPi * r) * cos_a;
    }
  }
  return sum;
}

bool sample_probe(const EmbreeScene& scene, const SurfaceInteraction& si, const RgbProfile& profile, const Vec4& u,
                  ProbeSample* out, uint64_t* rays) {
  // Technique: axis (s, t, n) and channel from u.x.
  float ux = u.x;
  int a;
  if (ux < kAxisProb[0]) {
    a = 0;
    ux /= kAxisProb[0];
  } else if (ux < kAxisProb[0] + kAxisProb[1]) {
    a = 1;
    ux = (ux - kAxisProb[0]) / kAxisProb[1];
  } else {
    a = 2;
    ux = (ux - kAxisProb[0] - kAxisProb[1]) / kAxisProb[2];
  }
  const int c = std::min(static_cast<int>(ux * 3.0f), 2);
  const float r_max = profile.r_max(c);
  if (!(r_max > 0.0f)) return false;

  const Frame f(si.ng);
  const Vec3 axes[3] = {f.s, f.t, f.n};
  const Vec3& axis = axes[a];
  const Vec3& e1 = axes[(a + 1) % 3];
  const Vec3& e2 = axes[(a + 2) % 3];
  const float r = profile.sample_radius(c, u.y);
  const float phi = kTwoPi * u.z;
  const float half = std::sqrt(std::max(r_max * r_max - r * r, 0.0f));
  if (!(half > 0.0f)) return false;
  const Vec3 centre = si.p + r * (std::cos(phi) * e1 + std::sin(phi) * e2);
  const Ray probe{centre + half * axis, -axis, 2.0f * half};

  SurfaceInteraction hits[kMaxProbeHits];
  const int n = scene.intersect_shape(probe, si.shape, si.instance, hits, kMaxProbeHits, rays);
  if (n == 0) return false;
  const int k = std::min(static_cast<int>(u.w * n), n - 1);
  const SurfaceInteraction& hit = hits[k];
  const float pdf = probe_pdf(si.p, si.ng, hit.p, hit.ng, profile);
  if (!(pdf > 0.0f)) return false;
  out->si = hit;
  out->weight = profile.eval(glm::length(hit.p - si.p)) * (static_cast<float>(n) / pdf);
  return true;
}

}  // namespace kozu
