// The baseline for bench_sggx: the angular-Gaussian fiber microflake distribution of Jakob, Arbree, Moon, Bala &
// Marschner 2010 ("A radiative transfer framework for rendering materials with anisotropic structure", §5) as
// used by Zhao, Jakob, Marschner & Bala 2011 (refs [8], [21] of Heitz et al. 2015, "The SGGX
// Microflake Distribution", whose Fig. 14 compares against this
// model's implementation in Mitsuba 0.5, microflake_fiber.h), implemented here as those renderers do.
//
//   D(ωm) = exp(−(ωm·t)² / (2γ²)) / ((2π)^{3/2} γ erf(1/(√2 γ)))     normalised: ∫ D dωm = 1
//     (flake normals concentrated about the great circle ⟂ the fiber tangent t; γ the angular deviation)
//   σ(ω)  = ∫⟨ω, ωm⟩ D(ωm) dωm (seed eq. 4, clamped cosine: half of Jakob's ∫|ω·ωm| D), a function of |ω·t| only:
//     precomputed at construction in a 512-entry table over |ω·t| in [0, 1] (the φ integral in closed form, the
//     θ integral by 64-panel 8-point Gauss–Legendre), linearly interpolated at run time
//   specular phase  f_p(ωi → ωo) = D(ωh) / (4 σ(ωi))   (seed eq. 24, Jakob eq. 13 with this σ)
//   VNDF sampling   by rejection, as in Jakob 2010 / Mitsuba: draw ωm ~ D (the truncated Gaussian in ωm·t by
//     the inverse error function, the azimuth uniform) and accept with probability |ωi·ωm|, flipping ωm to ωi's
//     side. Expected iterations 1 / (2σ(ωi)): ≈ π/2 across the fiber, ≈ 1.25/γ along it.
//   diffuse phase   eq. 25/26 on the same VNDF sampler (not in those papers; for a like-for-like benchmark row).
// Not used by the renderer; header-only so that only the benchmark compiles it.
#pragma once

#include "core/frame.h"
#include "core/rng.h"
#include "core/warp.h"
#include "materials/microfacet.h"
#include "media/phase.h"

#include <cmath>
#include <numbers>
#include <vector>

namespace kozu::bench {

class AngularGaussianFiber {
 public:
  static constexpr int kTableSize = 512;

  AngularGaussianFiber(const Vec3& tangent, float gamma)
      : frame_(glm::normalize(tangent)), gamma_(gamma), inv_two_gamma2_(1.0f / (2.0f * gamma * gamma)) {
    const double g = gamma;
    erf_bound_ = static_cast<float>(std::erf(1.0 / (std::numbers::sqrt2 * g)));
    norm_ = static_cast<float>(1.0 / (std::pow(2.0 * std::numbers::pi, 1.5) * g * std::erf(1.0 / (std::numbers::sqrt2 * g))));
    table_.resize(kTableSize);
    for (int i = 0; i < kTableSize; ++i) table_[static_cast<size_t>(i)] = static_cast<float>(projected_area_quadrature(double(i) / (kTableSize - 1)));
  }

  const Vec3& tangent() const { return frame_.n; }
  float gamma() const { return gamma_; }

  float D(const Vec3& wm) const {
    const float c = glm::dot(wm, frame_.n);
    return norm_ * std::exp(-c * c * inv_two_gamma2_);
  }

  // Table lookup over |ω·t|.
  float projected_area(const Vec3& w) const {
    const float x = std::min(std::abs(glm::dot(w, frame_.n)), 1.0f) * (kTableSize - 1);
    const int i = std::min(static_cast<int>(x), kTableSize - 2);
    const float f = x - static_cast<float>(i);
    return table_[static_cast<size_t>(i)] * (1.0f - f) + table_[static_cast<size_t>(i + 1)] * f;
  }

  // ∫⟨ω, ωm⟩ D dωm for ω·t = c, directly: with ωm = (sinθ cosφ, sinθ sinφ, z) about t and ω = (√(1−c²), 0, c),
  // ∫ max(A cos φ + B, 0) dφ = 2 (A sin φ1 + B φ1), φ1 = acos(−B/A), A = √(1−c²) sinθ, B = c z.
  double projected_area_quadrature(double c) const {
    static constexpr double kX[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290, -0.1834346424956498,
                                     0.1834346424956498,  0.5255324099163290,  0.7966664774136267,  0.9602898564975363};
    static constexpr double kW[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066748715737, 0.3626837833783620,
                                     0.3626837833783620, 0.3137066748715737, 0.2223810344533745, 0.1012285362903763};
    constexpr int kPanels = 64;
    const double g2 = 2.0 * double(gamma_) * gamma_, s = std::sqrt(std::max(0.0, 1.0 - c * c));
    double sum = 0;
    for (int p = 0; p < kPanels; ++p)
      for (int k = 0; k < 8; ++k) {
        const double z = -1.0 + (p + 0.5 * (kX[k] + 1.0)) * (2.0 / kPanels);
        const double a = s * std::sqrt(std::max(0.0, 1.0 - z * z)), b = c * z;
        double ring;
        if (b >= a) ring = 2.0 * std::numbers::pi * b;
        else if (b <= -a) ring = 0.0;
        else {
          const double phi1 = std::acos(-b / a);
          ring = 2.0 * (a * std::sin(phi1) + b * phi1);
        }
        sum += 0.5 * kW[k] * (2.0 / kPanels) * ring * std::exp(-z * z / g2);
      }
    return sum * norm_;
  }

  // One ωm ~ D: z = ωm·t from the Gaussian truncated to [−1, 1] by the inverse error function.
  Vec3 sample_D(Pcg32& rng) const {
    const float u1 = rng.next_float(), u2 = rng.next_float();
    const float z = std::clamp(std::numbers::sqrt2_v<float> * gamma_ * erf_inv((2.0f * u1 - 1.0f) * erf_bound_), -1.0f, 1.0f);
    const float r = safe_sqrt(1.0f - z * z), phi = kTwoPi * u2;
    return frame_.to_world(Vec3(r * std::cos(phi), r * std::sin(phi), z));
  }

  // The VNDF D_ωi by rejection.
  Vec3 sample_visible(const Vec3& wi, Pcg32& rng) const {
    for (;;) {
      const Vec3 m = sample_D(rng);
      const float c = glm::dot(wi, m);
      if (rng.next_float() < std::abs(c)) return c < 0.0f ? -m : m;
    }
  }

 private:
  Frame frame_;
  float gamma_, inv_two_gamma2_, erf_bound_ = 0, norm_ = 0;
  std::vector<float> table_;
};

class AngularGaussianSpecularPhase final : public PhaseFunction {
 public:
  explicit AngularGaussianSpecularPhase(const AngularGaussianFiber* d) : d_(d) {}
  float eval(const Vec3& wo, const Vec3& wi, Pcg32&) const override { return pdf(wo, wi); }
  float pdf(const Vec3& wo, const Vec3& wi) const override {
    const Vec3 h = wo + wi;
    const float len2 = glm::dot(h, h);
    if (!(len2 > 1e-12f)) return 0.0f;
    const float sigma = d_->projected_area(wo);
    return sigma > 0.0f ? d_->D(h / std::sqrt(len2)) / (4.0f * sigma) : 0.0f;
  }
  PhaseSample sample(const Vec3& wo, const Vec2&, Pcg32& rng) const override {
    const Vec3 wm = d_->sample_visible(wo, rng);
    PhaseSample s;
    s.wi = glm::normalize(reflect(wo, wm));
    s.pdf = pdf(wo, s.wi);
    s.f = s.pdf;  // f_p sampled exactly
    return s;
  }

 private:
  const AngularGaussianFiber* d_;
};

class AngularGaussianDiffusePhase final : public PhaseFunction {
 public:
  explicit AngularGaussianDiffusePhase(const AngularGaussianFiber* d) : d_(d) {}
  float eval(const Vec3& wo, const Vec3& wi, Pcg32& rng) const override {
    return std::max(glm::dot(wi, d_->sample_visible(wo, rng)), 0.0f) * kInvPi;
  }
  float pdf(const Vec3&, const Vec3&) const override { return kInv4Pi; }
  PhaseSample sample(const Vec3& wo, const Vec2&, Pcg32& rng) const override {
    const Vec3 wm = d_->sample_visible(wo, rng);
    const float u1 = rng.next_float();
    PhaseSample s;
    s.wi = glm::normalize(Frame(wm).to_world(warp::square_to_cosine_hemisphere(Vec2(u1, rng.next_float()))));
    s.pdf = kInv4Pi;  // the MIS proxy
    s.f = s.pdf;      // weight 1: the flake's Lambertian lobe is sampled exactly
    return s;
  }

 private:
  const AngularGaussianFiber* d_;
};

}  // namespace kozu::bench
