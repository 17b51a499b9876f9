// The BSDF interface and kozu's direction conventions, fixed here once for every model.
//
// Conventions (all BSDFs, phase functions and their tests follow these):
//  - Directions are unit vectors in the local shading frame: the shading normal is +z.
//  - `wo` is given: it points from the surface towards the previous path vertex (the camera
//    side). `wi` is sampled: it points towards the next vertex (the light side). Both point away
//    from the surface.
//  - `eval(wo, wi)` returns f(wo, wi) * |cos(theta_i)|: the cosine of the sampled direction is
//    included, so path throughput is updated by eval / pdf.
//  - `pdf(wo, wi)` is a density per unit solid angle of wi.
//  - Delta (perfectly specular) lobes are never returned by eval/pdf; `sample` returns them with
//    `delta = true`, `f` the coefficient of the Dirac and `pdf` the discrete probability of
//    choosing that lobe, so f / pdf is still the throughput weight.
//  - Transmission in TransportMode::Radiance includes the 1/eta^2 radiance scaling (eta = ratio of
//    the IOR on wi's side to the IOR on wo's side); TransportMode::Importance omits it (Veach 1997, §5.2).
#pragma once

#include "core/color.h"
#include "core/frame.h"
#include "core/ltc.h"

#include <array>
#include <optional>

namespace kozu {

enum class TransportMode { Radiance, Importance };

// Lobe flags, combinable.
enum BsdfFlags : uint32_t {
  kBsdfNone = 0,
  kBsdfReflection = 1u << 0,
  kBsdfTransmission = 1u << 1,
  kBsdfDiffuse = 1u << 2,
  kBsdfGlossy = 1u << 3,
  kBsdfSpecular = 1u << 4,  // Dirac delta lobe
};

struct BsdfSample {
  Vec3 wi;
  Rgb f{0.0f};         // f * |cos theta_i| (delta lobes: the Dirac's coefficient)
  float pdf = 0;       // solid-angle density (delta lobes: the lobe's discrete probability)
  uint32_t flags = 0;  // the lobe that was sampled
  float eta = 1.0f;    // relative IOR across the interface along wi (1 for reflection)
  bool delta() const { return (flags & kBsdfSpecular) != 0; }
  bool valid() const { return pdf > 0.0f; }
  Rgb weight() const { return pdf > 0.0f ? f / pdf : Rgb(0.0f); }
};

// One lobe of a BSDF's approximation by linearly transformed cosines (lights/ltc.h), for analytic direct lighting
// from polygon lights (integrators/path.cpp, "direct": "ltc"): f(wo, wi) |cos θi| ≈ Σ weight · D(wi), D in the
// local shading frame. The approximation need not be good for "ltc" to be unbiased, only for it to be precise.
struct LtcLobe {
  Ltc ltc;
  Rgb weight{0.0f};
};
inline constexpr int kMaxLtcLobes = 4;  // standard: clearcoat, metal, specular, base

// True when flags include a lobe that is not a Dirac delta (so light sampling can reach it).
inline bool has_non_delta(uint32_t flags) { return (flags & (kBsdfDiffuse | kBsdfGlossy)) != 0; }

class Bsdf {
 public:
 protected:
  // Not virtual: BSDFs live in an arena and are never deleted through this interface.
  ~Bsdf() = default;

 public:
  virtual Rgb eval(const Vec3& wo, const Vec3& wi, TransportMode mode = TransportMode::Radiance) const = 0;
  // u_lobe chooses between lobes, u chooses the direction within it. Returns pdf = 0 on failure.
  virtual BsdfSample sample(const Vec3& wo, float u_lobe, const Vec2& u,
                            TransportMode mode = TransportMode::Radiance) const = 0;
  virtual float pdf(const Vec3& wo, const Vec3& wi) const = 0;
  // eval and pdf together (next-event estimation needs both); models override it when the two
  // share work.
  virtual Rgb eval_pdf(const Vec3& wo, const Vec3& wi, float* pdf_out,
                       TransportMode mode = TransportMode::Radiance) const {
    *pdf_out = pdf(wo, wi);
    return eval(wo, wi, mode);
  }
  // Union of the lobes this BSDF has.
  virtual uint32_t flags() const = 0;
  // The LTC lobes approximating eval(wo, ·) (up to kMaxLtcLobes, written to out), or 0 when the model has none
  // for this wo (direct lighting then samples as usual). `toward` (on wo's side) points at the light's centre:
  // models that are not LTCs in shape weigh their cosine lobe by their value there, exact for small lights.
  virtual int ltc_lobes(const Vec3& /*wo*/, const Vec3& /*toward*/, LtcLobe* /*out*/) const { return 0; }
  // The lobes with `toward` the normal on wo's side: those of no light in particular (the albedo feature, the lobe
  // that shapes light samples, the count the path's emission asks for).
  int ltc_lobes_at_normal(const Vec3& wo, LtcLobe* out) const {
    return ltc_lobes(wo, Vec3(0.0f, 0.0f, wo.z >= 0.0f ? 1.0f : -1.0f), out);
  }
  // The sum of the LTC lobes' weights at wo (ltc_lobes_at_normal): the directional albedo, since each lobe is weighted
  // by its part's exact albedo (LtcLobes.EnergyMatchesTheAlbedo); none where there are no lobes.
  std::optional<Rgb> ltc_albedo(const Vec3& wo) const {
    std::array<LtcLobe, kMaxLtcLobes> lobes;
    const int n = ltc_lobes_at_normal(wo, lobes.data());
    if (n <= 0) return std::nullopt;
    Rgb sum(0.0f);
    for (int k = 0; k < n; ++k) sum += lobes[static_cast<size_t>(k)].weight;
    return sum;
  }
  // The roughness α of its narrowest LTC lobe (the geometric mean of an anisotropic one's), 1 where it has none but
  // clamped cosines: a test far cheaper than ltc_lobes of whether a lobe may be narrow enough to shape light samples
  // (integrators/lobe_light_sampler.h).
  virtual float narrowest_ltc_alpha() const { return 1.0f; }

  bool has_non_delta() const { return kozu::has_non_delta(flags()); }

 protected:
  // The sample at wi drawn by one of a mixture's strategies: value and pdf come from eval_pdf (the
  // mixture's pdf), which keeps one-sample MIS over the lobes consistent. Invalid (pdf 0) when
  // eval_pdf rejects wi.
  BsdfSample sample_at(const Vec3& wo, const Vec3& wi, uint32_t flags, TransportMode mode, float eta = 1.0f) const {
    BsdfSample s;
    s.f = eval_pdf(wo, wi, &s.pdf, mode);
    if (!(s.pdf > 0.0f)) return BsdfSample{};
    s.wi = wi;
    s.flags = flags;
    s.eta = eta;
    return s;
  }
};

// A BSDF whose value and pdf come out of one computation: it implements eval_pdf alone, and eval and pdf are
// derived from it here, once.
class JointBsdf : public Bsdf {
 public:
  Rgb eval(const Vec3& wo, const Vec3& wi, TransportMode mode = TransportMode::Radiance) const final {
    float p;
    return eval_pdf(wo, wi, &p, mode);
  }
  float pdf(const Vec3& wo, const Vec3& wi) const final {
    float p;
    eval_pdf(wo, wi, &p, TransportMode::Radiance);
    return p;
  }
  Rgb eval_pdf(const Vec3& wo, const Vec3& wi, float* pdf_out,
               TransportMode mode = TransportMode::Radiance) const override = 0;

 protected:
  ~JointBsdf() = default;
};

}  // namespace kozu
