// homogeneous: a medium with constant coefficients and a Henyey–Greenstein (or isotropic) phase function.
//
//   σt = density (per channel),  σs = albedo · σt
// Its majorant is one segment of max_c σt: delta tracking then samples exact exponential flights.
//
// Parameters
//   density  rgb or float  1            ≥ 0   extinction coefficient σt per scene unit
//   albedo   rgb or float  0.8          [0,1] single-scattering albedo σs/σt
//   phase    "isotropic" | {"type": "hg", "g": g}   "isotropic"
#pragma once

#include "media/hg_phase.h"
#include "media/medium.h"

namespace kozu {

class JsonObject;

class HomogeneousMedium final : public Medium {
 public:
  HomogeneousMedium(const Rgb& sigma_t, const Rgb& albedo, float g)
      : props_{sigma_t, sigma_t * albedo}, majorant_(max_component(sigma_t)), phase_(g) {}
  static Deferred<Medium> parse(const JsonObject& desc);
  MediumProperties properties(const Vec3&, const Vec3&) const override { return props_; }
  const PhaseFunction* phase(const Vec3&, Arena&) const override { return &phase_; }
  const MediumProperties* homogeneous() const override { return &props_; }
  void majorants(const Vec3&, const Vec3&, float t0, float t1, MajorantVisitor& v) const override {
    v.segment(t0, t1, majorant_);
  }

 private:
  MediumProperties props_;
  float majorant_;
  HgPhase phase_;
};

// Reads "phase": "isotropic" or {"type": "hg", "g": g} and returns g.
float read_hg_phase(const JsonObject& desc);

}  // namespace kozu
