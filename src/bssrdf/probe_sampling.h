// Probe-ray sampling of a BSSRDF's second surface point: given the point xo where light is seen to
// enter (or leave) a subsurface object, find a point xi on the same object with density close to the
// radial profile R(|xo − xi|).
//
// Technique (k = axis a × color channel c), chosen with probability P_a · 1/3: draw a radius r from
// channel c's profile (normalized_diffusion.h, truncated at r_max,c, the radius holding kProbeFraction
// of its energy) and an angle φ; the point on the disk around xo perpendicular to axis a (the normal
// with P = 1/2, either tangent with P = 1/4) at (r, φ) is the centre of a probe segment along a of
// half-length sqrt(r_max,c² − r²), so every surface point within r_max,c of xo can be reached. The
// segment collects every hit with the same shape (other shapes are stepped over, so neighbouring
// objects do not bleed into each other); one of the n hits is chosen uniformly.
//
// Density of technique k at xi, per unit surface area, without the 1/n of the hit choice:
//   q_k(xi) = pdf_c(r_a) / (2π r_a) · |n_i · a|,   r_a = |xi − xo| projected on the plane ⟂ a,
// zero when |xi − xo| > r_max,c. One-sample MIS with the balance heuristic over the nine techniques,
// with the weights built from q (which partition unity whatever the hit counts along the other axes),
// gives the unbiased estimator
//   weight = R(|xi − xo|) · n / Σ_k P_k q_k(xi)
// (the n of the traced segment cancels its own 1/n; Veach 1997 §9.2.4 for one-sample MIS).
// This is the usual probe scheme of production BSSRDFs (King, Kulla, Conty, Fajardo 2013, "BSSRDF
// importance sampling", SIGGRAPH talk); the radius sampling is exact (Christensen & Burley 2015 eq. 11).
#pragma once

#include "bssrdf/normalized_diffusion.h"
#include "core/color.h"
#include "geometry/interaction.h"

#include <array>

namespace kozu {

class EmbreeScene;

// The fraction of each channel's profile energy within its probe radius; the rest (1e-5 A) is lost.
inline constexpr float kProbeFraction = 0.99999f;
// Hits kept per probe segment; more are ignored (a bias only for surfaces folded that many times).
inline constexpr int kMaxProbeHits = 16;

// Three channels' profiles with the radius sampling truncated to [0, r_max].
class RgbProfile {
 public:
  RgbProfile() = default;
  explicit RgbProfile(const std::array<NormalizedDiffusion, 3>& channels);

  Rgb eval(float r) const;  // R(r) per channel
  // Truncated radius density of channel c and its sampling; r_max(c) bounds the support.
  float pdf_radius(int c, float r) const;
  float sample_radius(int c, float u) const;
  float r_max(int c) const { return r_max_[c]; }
  const NormalizedDiffusion& channel(int c) const { return ch_[c]; }
  Rgb albedo() const { return Rgb(ch_[0].albedo(), ch_[1].albedo(), ch_[2].albedo()); }

 private:
  std::array<NormalizedDiffusion, 3> ch_;
  std::array<float, 3> r_max_{0, 0, 0};
};

struct ProbeSample {
  SurfaceInteraction si;  // the second point (its shading frame as the shape reports it)
  Rgb weight{0.0f};       // R(|xi − xo|) / pdf(xi), MIS over axes and channels
};

// Samples xi around xo (si's point, with its geometric normal) on si.shape. u.x picks the technique,
// (u.y, u.z) the disk point, u.w the hit. Returns false when the segment finds no hit.
// *rays grows by the number of Embree queries.
bool sample_probe(const EmbreeScene& scene, const SurfaceInteraction& si, const RgbProfile& profile, const Vec4& u,
                  ProbeSample* out, uint64_t* rays);

// Σ_k P_k q_k(xi) for the point xi with unit normal ni (exposed for tests).
float probe_pdf(const Vec3& xo, const Vec3& no, const Vec3& xi, const Vec3& ni, const RgbProfile& profile);

}  // namespace kozu
