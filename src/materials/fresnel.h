// Fresnel reflectance of smooth interfaces: dielectric (real IOR) and conductor (complex IOR).
//
// Dielectric: the unpolarised Fresnel equations (Born & Wolf §1.5). Conductor: the exact
// unpolarised reflectance for a complex index eta + i k (Born & Wolf §14.2, in the a^2 + b^2 form),
// evaluated per RGB channel at 650/550/450 nm as ushiostarfish 2018 (blog posts of ushiostarfish's diary)
// proposes. That source itself uses a cheaper approximation (r_perp, r_par built from n^2 + k^2, as in pbrt-v2);
// it agrees with the exact form at normal incidence and is available as fresnel_conductor_approx
// (conductor `"fresnel": "approximate"`); the exact form is the default.
#pragma once

#include "core/color.h"
#include "core/math.h"

namespace kozu {

// Reflectance at a dielectric interface. cos_i is the cosine on the incident side (sign tells the
// side: > 0 means the incident direction is outside, where the relative IOR is eta = n_inside / n_outside).
inline float fresnel_dielectric(float cos_i, float eta) {
  cos_i = std::clamp(cos_i, -1.0f, 1.0f);
  if (cos_i < 0.0f) {
    eta = 1.0f / eta;
    cos_i = -cos_i;
  }
  const float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.0f) return 1.0f;  // total internal reflection
  const float cos_t = safe_sqrt(1.0f - sin2_t);
  const float r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  const float r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  return 0.5f * (r_parl * r_parl + r_perp * r_perp);
}

// Exact conductor reflectance for complex IOR eta + i k (relative to the outside medium).
inline float fresnel_conductor(float cos_i, float eta, float k) {
  cos_i = std::clamp(std::abs(cos_i), 0.0f, 1.0f);
  const float cos2 = cos_i * cos_i;
  const float sin2 = 1.0f - cos2;
  const float eta2 = eta * eta, k2 = k * k;
  const float t0 = eta2 - k2 - sin2;
  const float a2b2 = std::sqrt(std::max(t0 * t0 + 4.0f * eta2 * k2, 0.0f));  // a^2 + b^2
  const float a = safe_sqrt(0.5f * (a2b2 + t0));
  const float t1 = a2b2 + cos2;
  const float t2 = 2.0f * a * cos_i;
  const float rs = (t1 - t2) / (t1 + t2);
  const float t3 = cos2 * a2b2 + sin2 * sin2;
  const float t4 = t2 * sin2;
  const float rp = rs * (t3 - t4) / (t3 + t4);
  const float r = 0.5f * (rp + rs);
  return std::isfinite(r) ? r : 1.0f;
}

// ushiostarfish 2018's approximation (section "多重拡散項の近似"):
//   r⊥ = (n² + k² − 2n cos θ + cos² θ) / (n² + k² + 2n cos θ + cos² θ)
//   r∥ = ((n² + k²) cos² θ − 2n cos θ + 1) / ((n² + k²) cos² θ + 2n cos θ + 1),  F = (r⊥ + r∥) / 2
// Evaluated in double: n² + k² overflows float for n or k above ~1.8e19, which any float input may be.
inline float fresnel_conductor_approx(float cos_i, float eta, float k) {
  const double c = std::clamp(std::abs(double(cos_i)), 0.0, 1.0);
  const double n = eta, nk2 = n * n + double(k) * k;
  const double two_nc = 2.0 * n * c;
  const double r_perp = (nk2 - two_nc + c * c) / (nk2 + two_nc + c * c);
  const double r_par = (nk2 * c * c - two_nc + 1.0) / (nk2 * c * c + two_nc + 1.0);
  return static_cast<float>(0.5 * (r_perp + r_par));
}

inline Rgb fresnel_conductor(float cos_i, const Rgb& eta, const Rgb& k) {
  return Rgb(fresnel_conductor(cos_i, eta.r, k.r), fresnel_conductor(cos_i, eta.g, k.g),
             fresnel_conductor(cos_i, eta.b, k.b));
}

// A conductor's Fresnel term per RGB channel: F = 1 (`perfect`, the white-furnace conductor), the
// exact form, or ushiostarfish 2018's approximation.
struct ConductorFresnel {
  Rgb eta{1.0f}, k{0.0f};
  bool perfect = true;
  bool approximate = false;
  Rgb eval(float cos_i) const {
    if (perfect) return Rgb(1.0f);
    if (!approximate) return fresnel_conductor(cos_i, eta, k);
    return Rgb(fresnel_conductor_approx(cos_i, eta.r, k.r), fresnel_conductor_approx(cos_i, eta.g, k.g),
               fresnel_conductor_approx(cos_i, eta.b, k.b));
  }
};

// Refracts wi (pointing away from the surface, on the side of n) through an interface with
// relative IOR eta (transmitted side / incident side). Returns false on total internal reflection.
inline bool refract(const Vec3& wi, const Vec3& n, float eta, Vec3* wt) {
  const float cos_i = glm::dot(n, wi);
  const float sin2_i = std::max(0.0f, 1.0f - cos_i * cos_i);
  const float sin2_t = sin2_i / (eta * eta);
  if (sin2_t >= 1.0f) return false;
  const float cos_t = safe_sqrt(1.0f - sin2_t);
  *wt = -wi / eta + (cos_i / eta - cos_t) * n;
  return true;
}

}  // namespace kozu
