// Microfacet theory: the GGX (Trowbridge–Reitz) and Beckmann normal distributions, isotropic or
// anisotropic, with the exact Smith masking function, height-correlated shadowing-masking, the
// distribution of visible normals (VNDF) and its exact sampling for both distributions.
//
// Source: the "Microfacet入門" (1), (2) blog posts of ushiostarfish's diary, 2018 (ushiostarfish 2018; after Heitz
// 2014, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs"):
//   D normalisation  ∫ D(ωm) ⟨ωm, ωg⟩ dωm = 1                      ushiostarfish 2018 (Microfacet入門(2), eq. of P22)
//   slope space      P22(x̃, ỹ) = D(ωm) cos⁴θm, ωm = (−x̃, −ỹ, 1)/|·|  ushiostarfish 2018 (slope-space section)
//   Smith Λ          Λ(ωo) = ∫ (q − cot θo) P2(q) dq, q > cot θo    ushiostarfish 2018 (Smith derivation)
//   Beckmann Λ       Λ = (erf(a) − 1)/2 + exp(−a²)/(2a√π), a = 1/(α tan θ)   ushiostarfish 2018
//   GGX Λ            Λ = (−1 + sqrt(1 + 1/a²))/2                                ushiostarfish 2018
//   G1               G1(ωo, ωm) = χ⁺(ωo·ωm) / (1 + Λ(ωo))                       ushiostarfish 2018
//   G2               G2 = χ⁺ / (1 + Λ(ωo) + Λ(ωi)) (height-correlated)          ushiostarfish 2018
//   VNDF             D_ωo(ωm) = G1(ωo, ωm) ⟨ωo, ωm⟩ D(ωm) / cos θo             (Heitz & d'Eon 2014, eq. 2)
// Anisotropy by stretching (Heitz 2014 §5.3): α(φ)² = cos²φ αx² + sin²φ αy².
//
// VNDF sampling
//   GGX: Dupuy & Benyoub 2023, "Sampling Visible GGX Normals with Spherical Caps": in the stretched
//   (α = 1) configuration the visible normals are ωo + c with c uniform on the spherical cap
//   z ≥ −ωo.z. Exact.
//   Beckmann: Heitz & d'Eon 2014 slope-space sampling, derived here for the separable Gaussian
//   P22 = exp(−x̃² − ỹ²)/π in the stretched configuration: ỹ is N(0, 1/2) independently of x̃ and
//   x̃ has the density ∝ (cot θ − x̃) exp(−x̃²) on x̃ < cot θ, whose CDF
//     C(x) = cot θ · (√π/2)(1 + erf x) + exp(−x²)/2
//   is inverted by safeguarded Newton iteration (bisection bracket kept, so it always converges).
//   Exact up to the solver tolerance (relative 1e-7 in C).
#pragma once

#include "core/frame.h"
#include "core/math.h"

#include <cmath>
#include <string_view>

namespace kozu {

enum class MicrofacetType { GGX, Beckmann };

class MicrofacetDistribution {
 public:
  // Roughness below this is treated as a perfectly smooth (delta) surface by the materials: the
  // NDF is then too narrow for float arithmetic.
  static constexpr float kMinAlpha = 1e-3f;

  MicrofacetDistribution() = default;
  MicrofacetDistribution(MicrofacetType type, float alpha_x, float alpha_y)
      : type_(type), ax_(std::max(alpha_x, kMinAlpha)), ay_(std::max(alpha_y, kMinAlpha)) {}

  MicrofacetType type() const { return type_; }
  float alpha_x() const { return ax_; }
  float alpha_y() const { return ay_; }
  bool isotropic() const { return ax_ == ay_; }
  // One α for tables indexed by a scalar roughness: the root mean square of αx and αy (exact for
  // isotropic). The loss of an anisotropic surface follows its larger α more than the geometric mean
  // suggests: for (0.1, 0.5) the RMS restores the furnace to within a few % where sqrt(αx αy) left 11 %.
  float effective_alpha() const { return std::sqrt(0.5f * (ax_ * ax_ + ay_ * ay_)); }

  // Normal distribution D(ωm) for a micronormal in the local frame (zero below the horizon).
  float D(const Vec3& m) const {
    if (m.z <= 0.0f) return 0.0f;
    const float cos2 = m.z * m.z;
    // tan²θ (cos²φ/αx² + sin²φ/αy²) = (mx²/αx² + my²/αy²)/mz²
    const float e = (m.x * m.x / (ax_ * ax_) + m.y * m.y / (ay_ * ay_)) / cos2;
    if (type_ == MicrofacetType::GGX) {
      const float d = 1.0f + e;
      return 1.0f / (kPi * ax_ * ay_ * cos2 * cos2 * d * d);
    }
    return std::exp(-e) / (kPi * ax_ * ay_ * cos2 * cos2);
  }

  // Smith Λ(ω); symmetric in ω.z's sign (a two-sided microsurface seen from either side).
  float lambda(const Vec3& w) const {
    const float z2 = w.z * w.z;
    const float t = ax_ * ax_ * w.x * w.x + ay_ * ay_ * w.y * w.y;  // α(φ)² sin²θ
    if (t <= 0.0f) return 0.0f;                                     // normal incidence: nothing is masked
    if (z2 == 0.0f) return std::numeric_limits<float>::infinity();
    if (type_ == MicrofacetType::GGX) {
      // (−1 + sqrt(1 + α² tan²θ))/2, written to avoid cancellation when α² tan²θ is tiny.
      const float a2t2 = t / z2;
      return a2t2 / (1.0f + std::sqrt(1.0f + a2t2)) * 0.5f;
    }
    const float a = std::abs(w.z) / std::sqrt(t);  // 1/(α tan θ)
    if (a >= 4.5f) return 0.0f;                    // Λ < 1e-10: below float resolution
    // (erf(a) − 1)/2 + exp(−a²)/(2a√π) = (exp(−a²)/(a√π) − erfc(a))/2. The two terms cancel to a relative
    // 1/(2a²) of their size (1/40 at a = 4.5), so they are taken in double, from erfc rather than erf − 1;
    // in float the result lost all its digits past a ≈ 3 (15% error at a = 3.3).
    const double ad = a;
    return static_cast<float>(0.5 * (std::exp(-ad * ad) / (ad * 1.7724538509055160) - std::erfc(ad)));
  }

  // Masking of the macrosurface direction w (any micronormal on its visible side).
  float G1(const Vec3& w) const { return 1.0f / (1.0f + lambda(w)); }
  // Height-correlated masking-shadowing of wo and wi (the χ⁺ factors are the caller's).
  float G2(const Vec3& wo, const Vec3& wi) const { return 1.0f / (1.0f + lambda(wo) + lambda(wi)); }

  // Density of visible normals D_w(m) for w with w.z > 0 (per unit solid angle of m).
  float D_visible(const Vec3& w, const Vec3& m) const {
    const float wm = glm::dot(w, m);
    if (w.z <= 0.0f || wm <= 0.0f) return 0.0f;
    return G1(w) * wm * D(m) / w.z;
  }

  // Samples a visible micronormal for w (w.z > 0) from two uniform numbers; pdf = D_visible(w, m).
  Vec3 sample_visible(const Vec3& w, const Vec2& u) const {
    // Stretch to the α = 1 configuration.
    const Vec3 ws = glm::normalize(Vec3(ax_ * w.x, ay_ * w.y, w.z));
    const Vec2 slope = type_ == MicrofacetType::GGX ? Vec2(0.0f) : sample_beckmann_slopes(ws, u);
    Vec3 h;
    if (type_ == MicrofacetType::GGX) {
      // Spherical cap of directions with z >= -ws.z, uniformly (Dupuy & Benyoub 2023).
      const float phi = kTwoPi * u.x;
      const float z = std::fma(1.0f - u.y, 1.0f + ws.z, -ws.z);
      const float sin_theta = safe_sqrt(1.0f - z * z);
      h = Vec3(sin_theta * std::cos(phi), sin_theta * std::sin(phi), z) + ws;
    } else {
      h = Vec3(-slope.x, -slope.y, 1.0f);
    }
    // Unstretch: normals transform with the inverse transpose of the stretch.
    const Vec3 m = Vec3(ax_ * h.x, ay_ * h.y, std::max(h.z, 0.0f));
    const float len = glm::length(m);
    return len > 0.0f ? m / len : Vec3(0.0f, 0.0f, 1.0f);
  }

  // Slope-space helpers (stretched configuration α = 1 unless noted).
  // P22 of the configured distribution at slope (x̃, ỹ): D(ωm) cos⁴θm.
  float P22(float sx, float sy) const {
    const float e = sx * sx / (ax_ * ax_) + sy * sy / (ay_ * ay_);
    if (type_ == MicrofacetType::GGX) {
      const float d = 1.0f + e;
      return 1.0f / (kPi * ax_ * ay_ * d * d);
    }
    return std::exp(-e) / (kPi * ax_ * ay_);
  }
  static Vec3 slope_to_normal(float sx, float sy) { return glm::normalize(Vec3(-sx, -sy, 1.0f)); }
  static Vec2 normal_to_slope(const Vec3& m) { return Vec2(-m.x / m.z, -m.y / m.z); }

 private:
  // Beckmann visible slopes for the stretched direction ws (Heitz & d'Eon 2014, derived above),
  // rotated from the incidence plane to ws's azimuth.
  static Vec2 sample_beckmann_slopes(const Vec3& ws, const Vec2& u);

  MicrofacetType type_ = MicrofacetType::GGX;
  float ax_ = 0.5f, ay_ = 0.5f;
};

// Inverse error function (Giles 2010, "Approximating the erfinv function", single precision),
// refined by one Newton step so it is accurate to float rounding.
float erf_inv(float x);

// Parses "ggx" / "beckmann".
MicrofacetType microfacet_type_from_string(std::string_view s);

}  // namespace kozu
