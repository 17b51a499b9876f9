// The baseline for bench_sggx: the angular-Gaussian fiber microflake distribution of Jakob, Arbree, Moon, Bala &
// Marschner 2010 ("A radiative transfer framework for rendering materials with anisotropic structure", §5) as
// used by Zhao, Jakob, Marschner & Bala 2011 (refs [8], [21] of Heitz et al. 2015, "The SGGX Microflake
// Distribution", whose Fig. 14 times SGGX against this model's implementation in Mitsuba 0.5:
// src/phase/microflake.cpp and microflake_fiber.h). Each part below does what Mitsuba 0.5 does, at its cost;
// nothing of Mitsuba's code or tables is copied.
//
//   D(ωm) = exp(−(ωm·t)² / (2γ²)) / ((2π)^{3/2} γ erf(1/(√2 γ)))   normalised: ∫ D dωm = 1; one exp per call
//     (Mitsuba's pdfCosTheta, math::fastexp = expf), γ the angular deviation, t the fiber tangent.
//   σ(ω) = ∫⟨ω, ωm⟩ D(ωm) dωm (seed eq. 4, the clamped cosine; Mitsuba tabulates the unclamped ∫|ω·ωm| D = 2σ
//     and halves it in the phase function). Mitsuba evaluates σ as a degree-9 polynomial in sinθ (θ the angle
//     to t), summed with two running products (result += base·c_i; base *= sinθ), whose 10 coefficients it
//     interpolates at construction from a 100-row table of fits over γ. Here the coefficients are our own
//     least-squares fit of the same expansion to σ by quadrature, made at construction for each γ (so no
//     interpolation error between rows); the per-call cost is the same. fit_error() reports the fit's largest
//     relative error (Mitsuba states a mean absolute error of 3.2e-5 for its table).
//   VNDF sampling, by rejection as in Mitsuba's MicroflakePhaseFunction::sample: ωm ~ D, with cosθ found by
//     inverting the longitudinal CDF 0.5 (1 − erf(cosθ/(√2γ)) / erf(1/(√2γ))) with Brent's root finder
//     (Brent 1973; 100 iterations, tolerance 1e-6 in x and in the CDF, the function passed type-erased —
//     boost::function there, std::function here) and φ = 2πξ with a sine and a cosine; accepted with
//     probability |ωi·ωm| (at most 1000 tries), then flipped to ωi's side. Expected tries 1 / (2σ(ωi)).
//   specular phase  f_p(ωi → ωo) = D(ωh) / (4 σ(ωi))  (seed eq. 24, Jakob eq. 13), evaluated as Mitsuba does:
//     the fiber's Frame is built from its orientation on every call, and ωi, ωo taken to local coordinates.
//   diffuse phase   eq. 25/26 on the same VNDF sampler (not in those papers; a like-for-like benchmark row),
//     with a constant MIS pdf 1/4π, which favours the baseline.
// Not used by the renderer; header-only so that only the benchmark compiles it.
#pragma once

#include "core/frame.h"
#include "core/rng.h"
#include "core/warp.h"
#include "materials/microfacet.h"
#include "media/phase.h"

#include <array>
#include <cmath>
#include <functional>
#include <numbers>
#include <vector>

namespace kozu::bench {

// Brent's method for a root of f in [a, b] (f(a), f(b) of opposite signs), after Brent 1973, "Algorithms for
// Minimization without Derivatives", ch. 4: inverse quadratic interpolation or the secant step where they stay
// inside the bracket and shrink it fast enough, bisection otherwise. Stops when the bracket is below
// max(x_tol, rel_tol |b|) or |f(b)| ≤ f_tol. Returns the last iterate; `ok` false when f(a), f(b) share a sign.
inline float brent_root(const std::function<float(float)>& f, float a, float b, float x_tol, float rel_tol,
                        float f_tol, int max_iterations, bool& ok) {
  float fa = f(a), fb = f(b);
  ok = (fa <= 0.0f) != (fb <= 0.0f) || fa == 0.0f || fb == 0.0f;
  if (!ok) return b;
  float c = a, fc = fa, d = b - a, e = d;
  for (int it = 0; it < max_iterations; ++it) {
    if ((fb > 0.0f) == (fc > 0.0f)) {  // keep the root between b and c
      c = a;
      fc = fa;
      d = e = b - a;
    }
    if (std::abs(fc) < std::abs(fb)) {  // b is the best guess
      a = b;
      b = c;
      c = a;
      fa = fb;
      fb = fc;
      fc = fa;
    }
    const float tol = std::max(x_tol, rel_tol * std::abs(b));
    const float m = 0.5f * (c - b);
    if (std::abs(m) <= tol || std::abs(fb) <= f_tol) return b;
    if (std::abs(e) >= tol && std::abs(fa) > std::abs(fb)) {
      float p, q;
      const float s = fb / fa;
      if (a == c) {  // secant
        p = 2.0f * m * s;
        q = 1.0f - s;
      } else {  // inverse quadratic interpolation
        const float qa = fa / fc, r = fb / fc;
        p = s * (2.0f * m * qa * (qa - r) - (b - a) * (r - 1.0f));
        q = (qa - 1.0f) * (r - 1.0f) * (s - 1.0f);
      }
      if (p > 0.0f) q = -q;
      p = std::abs(p);
      if (2.0f * p < std::min(3.0f * m * q - std::abs(tol * q), std::abs(e * q))) {
        e = d;
        d = p / q;
      } else {
        d = m;
        e = d;
      }
    } else {
      d = m;
      e = d;
    }
    a = b;
    fa = fb;
    b += std::abs(d) > tol ? d : std::copysign(tol, m);
    fb = f(b);
  }
  return b;
}

class AngularGaussianFiber {
 public:
  static constexpr int kCoeffs = 10;

  AngularGaussianFiber(const Vec3& tangent, float gamma)
      : t_(glm::normalize(tangent)), gamma_(gamma), inv_two_gamma2_(1.0f / (2.0f * gamma * gamma)) {
    const double g = gamma;
    const double erf_bound = std::erf(1.0 / (std::numbers::sqrt2 * g));
    norm_ = static_cast<float>(1.0 / (std::pow(2.0 * std::numbers::pi, 1.5) * g * erf_bound));
    inv_erf_bound_ = static_cast<float>(1.0 / erf_bound);
    inv_sqrt2_gamma_ = static_cast<float>(1.0 / (std::numbers::sqrt2 * g));
    fit_sigma();
  }

  const Vec3& tangent() const { return t_; }
  float gamma() const { return gamma_; }
  double fit_error() const { return fit_error_; }

  // D from cosθ = ωm·t (Mitsuba's pdfCosTheta), and from a world-space ωm.
  float D_cos(float c) const { return norm_ * std::exp(-c * c * inv_two_gamma2_); }
  float D(const Vec3& wm) const { return D_cos(glm::dot(wm, t_)); }

  // σ from cosθ (the caller's dot with t, as Mitsuba's medium passes it).
  float sigma_cos(float cos_theta) const {
    const float sin_theta = std::sqrt(std::max(0.0f, 1.0f - cos_theta * cos_theta));
    float base = 1.0f, result = 0.0f;
    for (int i = 0; i < kCoeffs; ++i) {
      result += base * coeffs_[static_cast<size_t>(i)];
      base *= sin_theta;
    }
    return result;
  }
  float projected_area(const Vec3& w) const { return sigma_cos(glm::dot(w, t_)); }

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
    return sum * double(norm_);
  }

  // One ωm ~ D in the fiber's local frame (z = t): cosθ by Brent on the longitudinal CDF, φ uniform.
  Vec3 sample_D_local(Pcg32& rng) const {
    const float xi = rng.next_float(), u2 = rng.next_float();
    const std::function<float(float)> cdf = [this, xi](float cos_theta) {
      return 0.5f * (1.0f - std::erf(cos_theta * inv_sqrt2_gamma_) * inv_erf_bound_) - xi;
    };
    bool ok = false;
    const float z = brent_root(cdf, -1.0f, 1.0f, 1e-6f, 1e-6f, 1e-6f, 100, ok);
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z)), phi = kTwoPi * u2;
    return Vec3(r * std::cos(phi), r * std::sin(phi), z);
  }

  // The VNDF D_ωi by rejection, in the local frame; returns false after 1000 rejections.
  bool sample_visible_local(const Vec3& wi_local, Pcg32& rng, Vec3& wm) const {
    for (int it = 0; it < 1000; ++it) {
      const Vec3 m = sample_D_local(rng);
      const float c = glm::dot(wi_local, m);
      if (rng.next_float() < std::abs(c)) {
        wm = c < 0.0f ? -m : m;
        return true;
      }
    }
    return false;
  }

  Vec3 sample_visible(const Vec3& wi, Pcg32& rng) const {
    const Frame frame(t_);
    Vec3 m;
    return sample_visible_local(frame.to_local(wi), rng, m) ? frame.to_world(m) : wi;
  }

 private:
  // Least-squares fit of σ(sinθ) by the 10-term expansion on 256 points of sinθ in [0, 1] (Householder QR on
  // the Vandermonde matrix, in double).
  void fit_sigma() {
    constexpr int kPoints = 256;
    std::vector<std::array<double, kCoeffs>> A(kPoints);
    std::vector<double> y(kPoints);
    for (int i = 0; i < kPoints; ++i) {
      const double s = 0.5 - 0.5 * std::cos(std::numbers::pi * (i + 0.5) / kPoints);  // Chebyshev points
      double base = 1.0;
      for (int k = 0; k < kCoeffs; ++k, base *= s) A[size_t(i)][size_t(k)] = base;
      y[size_t(i)] = projected_area_quadrature(std::sqrt(std::max(0.0, 1.0 - s * s)));
    }
    for (int k = 0; k < kCoeffs; ++k) {  // Householder reflections
      double norm = 0;
      for (int i = k; i < kPoints; ++i) norm += A[size_t(i)][size_t(k)] * A[size_t(i)][size_t(k)];
      norm = std::sqrt(norm);
      const double alpha = A[size_t(k)][size_t(k)] > 0 ? -norm : norm;
      std::vector<double> v(kPoints, 0.0);
      for (int i = k; i < kPoints; ++i) v[size_t(i)] = A[size_t(i)][size_t(k)];
      v[size_t(k)] -= alpha;
      double vv = 0;
      for (int i = k; i < kPoints; ++i) vv += v[size_t(i)] * v[size_t(i)];
      if (vv == 0) continue;
      const auto reflect_column = [&](auto&& get) {
        double dot = 0;
        for (int i = k; i < kPoints; ++i) dot += v[size_t(i)] * get(i);
        const double f = 2.0 * dot / vv;
        for (int i = k; i < kPoints; ++i) get(i) -= f * v[size_t(i)];
      };
      for (int j = k; j < kCoeffs; ++j) reflect_column([&](int i) -> double& { return A[size_t(i)][size_t(j)]; });
      reflect_column([&](int i) -> double& { return y[size_t(i)]; });
    }
    std::array<double, kCoeffs> c{};
    for (int k = kCoeffs - 1; k >= 0; --k) {  // back substitution
      double r = y[size_t(k)];
      for (int j = k + 1; j < kCoeffs; ++j) r -= A[size_t(k)][size_t(j)] * c[size_t(j)];
      c[size_t(k)] = r / A[size_t(k)][size_t(k)];
    }
    for (int k = 0; k < kCoeffs; ++k) coeffs_[size_t(k)] = static_cast<float>(c[size_t(k)]);
    fit_error_ = 0;
    for (int i = 0; i <= 200; ++i) {
      const double cos_theta = i / 200.0, exact = projected_area_quadrature(cos_theta);
      fit_error_ = std::max(fit_error_, std::abs(sigma_cos(float(cos_theta)) - exact) / exact);
    }
  }

  Vec3 t_;
  float gamma_, inv_two_gamma2_, norm_ = 0, inv_erf_bound_ = 0, inv_sqrt2_gamma_ = 0;
  std::array<float, kCoeffs> coeffs_{};
  double fit_error_ = 0;
};

class AngularGaussianSpecularPhase final : public PhaseFunction {
 public:
  explicit AngularGaussianSpecularPhase(const AngularGaussianFiber* d) : d_(d) {}
  float eval(const Vec3& wo, const Vec3& wi, Pcg32&) const override { return pdf(wo, wi); }
  float pdf(const Vec3& wo, const Vec3& wi) const override {
    const Frame frame(d_->tangent());  // per call, as Mitsuba's eval
    const Vec3 lo = frame.to_local(wo), li = frame.to_local(wi), h = lo + li;
    const float len = std::sqrt(glm::dot(h, h));
    if (len == 0.0f) return 0.0f;
    return d_->D_cos(h.z / len) / (4.0f * d_->sigma_cos(lo.z));
  }
  PhaseSample sample(const Vec3& wo, const Vec2&, Pcg32& rng) const override {
    const Frame frame(d_->tangent());
    const Vec3 lo = frame.to_local(wo);
    Vec3 m;
    PhaseSample s;
    if (!d_->sample_visible_local(lo, rng, m)) return s;
    s.wi = frame.to_world(2.0f * glm::dot(lo, m) * m - lo);
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
