// sggx_medium: a microflake medium with the SGGX distribution (seed ../shared/seeds/000_bffe94c8223d9a8c.txt).
//
//   σt(ω) = ρ σ(ω)      eq. (2), σ(ω) = sqrt(ωᵀ S ω) eq. (11)
//   σs(ω) = α ρ σ(ω)    eq. (3), α per color channel
//   phase               specular (eq. 24) or diffuse (eq. 25, estimated by eq. 26) microflakes
//   majorant            ρ · sqrt(λmax(S)): bounds σt over all directions
// Homogeneous: constant ρ and S.
//
// Parameters
//   density       float   1          ≥ 0    ρ, the flakes' area density per scene unit³
//   albedo        rgb     0.8        [0, 1] α
//   phase         string  "specular" "specular" | "diffuse"
//   distribution  object  required   {"kind": "surface", "normal": n, "roughness": σ}  (eqs. 13–14)
//                                    {"kind": "fiber", "tangent": t, "roughness": σ}  (eqs. 15–16)
//                                    {"S": [Sxx, Syy, Szz, Sxy, Sxz, Syz]}            (eq. 10; positive definite)
#pragma once

#include "media/medium.h"
#include "media/sggx.h"

namespace kozu {

class JsonObject;

class SggxMedium final : public Medium {
 public:
  enum class Phase { Specular, Diffuse };
  SggxMedium(float density, const Rgb& albedo, const Sggx& S, Phase phase);
  static std::unique_ptr<Medium> create(const JsonObject& desc);

  MediumProperties properties(const Vec3& p, const Vec3& d) const override;
  const PhaseFunction* phase(const Vec3& p, Arena& arena) const override;
  void majorants(const Vec3& o, const Vec3& d, float t0, float t1, MajorantVisitor& v) const override;

 private:
  float density_;
  Rgb albedo_;
  Sggx S_;
  Phase phase_;
  float majorant_;
};

// Reads a "distribution" object (the three forms above) into S.
Sggx read_sggx_distribution(const JsonObject& d);

}  // namespace kozu
