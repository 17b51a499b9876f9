#include "materials/subsurface.h"

#include "core/json_reader.h"
#include "core/rng.h"
#include "materials/diffuse.h"
#include "materials/fresnel.h"
#include "materials/roughness.h"

#include <vector>

namespace kozu {

namespace {
// The dielectric always sees wo outside (+z): a hit on the back of a subsurface shape is treated as
// a hit from outside on that side.
inline Vec3 flip_z(const Vec3& w) { return Vec3(w.x, w.y, -w.z); }

// Rough boundary: T(μ) = ∫ f_t |cos θi| dωi over the lower hemisphere, estimated by sampling the BSDF
// (the estimator's mean is exactly that integral) on a jittered 128 × 128 grid, with the lobe choice
// stratified independently (Latin hypercube: a random permutation of the 16384 strata).
float transmittance_by_sampling(const Bsdf& bsdf, float mu) {
  mu = std::max(mu, 1e-3f);
  const Vec3 wo(std::sqrt(std::max(0.0f, 1.0f - mu * mu)), 0.0f, mu);
  constexpr int kGrid = 128, kN = kGrid * kGrid;
  Pcg32 rng(0x5eed5eedull, static_cast<uint64_t>(mu * 1e6f));
  std::vector<int> strata(kN);
  for (int k = 0; k < kN; ++k) strata[k] = k;
  for (int k = kN - 1; k > 0; --k) std::swap(strata[k], strata[rng.next_u32() % (k + 1)]);
  double sum = 0.0;
  for (int i = 0; i < kGrid; ++i) {
    for (int j = 0; j < kGrid; ++j) {
      const Vec2 u((i + rng.next_float()) / kGrid, (j + rng.next_float()) / kGrid);
      const float u_lobe = (strata[i * kGrid + j] + rng.next_float()) / kN;
      const BsdfSample s = bsdf.sample(wo, u_lobe, u, TransportMode::Importance);
      if (s.valid() && (s.flags & kBsdfTransmission)) sum += s.weight().r;
    }
  }
  return static_cast<float>(sum / (kGrid * kGrid));
}
}  // namespace

// ---- boundary ------------------------------------------------------------------------------------------

Rgb SubsurfaceBoundaryBsdf::eval_pdf(const Vec3& wo, const Vec3& wi, float* pdf_out, TransportMode mode) const {
  *pdf_out = 0.0f;
  if (wo.z * wi.z <= 0.0f) return Rgb(0.0f);  // transmission belongs to the BSSRDF
  if (wo.z < 0.0f) return inner_->eval_pdf(flip_z(wo), flip_z(wi), pdf_out, mode);
  return inner_->eval_pdf(wo, wi, pdf_out, mode);
}

BsdfSample SubsurfaceBoundaryBsdf::sample(const Vec3& wo, float u_lobe, const Vec2& u, TransportMode) const {
  const bool back = wo.z < 0.0f;
  // Importance mode: a transmitted sample's weight is the energy that enters, without 1/η².
  BsdfSample s = inner_->sample(back ? flip_z(wo) : wo, u_lobe, u, TransportMode::Importance);
  if (back) s.wi = flip_z(s.wi);
  return s;
}

// ---- exit ----------------------------------------------------------------------------------------------

Rgb SubsurfaceExitBsdf::eval(const Vec3&, const Vec3& wi, TransportMode) const {
  if (wi.z <= 0.0f) return Rgb(0.0f);
  return Rgb(t_->eval(wi.z) * wi.z * kInvPi / t_->average());
}

float SubsurfaceExitBsdf::pdf(const Vec3&, const Vec3& wi) const { return wi.z > 0.0f ? wi.z * kInvPi : 0.0f; }

BsdfSample SubsurfaceExitBsdf::sample(const Vec3&, float, const Vec2& u, TransportMode) const {
  BsdfSample s = sample_cosine_lobe(Vec3(0.0f, 0.0f, 1.0f), u);
  if (s.valid()) s.f = Rgb(t_->eval(s.wi.z) / t_->average()) * s.pdf;
  return s;
}

// ---- material ------------------------------------------------------------------------------------------

SubsurfaceMaterial::SubsurfaceMaterial(const Rgb& albedo, const Rgb& length, SubsurfaceParameterization p, float ior,
                                       bool smooth, const MicrofacetDistribution& d, MultiscatterMode mode)
    : boundary_(ior, smooth, d, mode) {
  std::array<NormalizedDiffusion, 3> ch;
  for (int c = 0; c < 3; ++c) ch[c] = NormalizedDiffusion::from_length(p, albedo[c], length[c]);
  profile_ = RgbProfile(ch);
  if (smooth || index_matched(ior)) {  // the boundary is smooth then too (dielectric.h)
    transmittance_ = AlbedoCurve([&](float mu) { return 1.0f - fresnel_dielectric(mu, ior); });
  } else {
    Arena arena;
    const Bsdf* b = boundary_.bsdf(SurfaceInteraction{}, arena);
    transmittance_ = AlbedoCurve([&](float mu) { return transmittance_by_sampling(*b, mu); });
  }
}

Deferred<Material> SubsurfaceMaterial::parse(const JsonObject& desc, const MaterialParseContext&) {
  const Rgb albedo = desc.get_rgb("albedo", Rgb(0.8f), Range::unit());
  const bool has_mfp = desc.has("mfp"), has_dmfp = desc.has("dmfp");
  if (has_mfp == has_dmfp)
    desc.fail(has_mfp ? "dmfp" : "mfp", "give exactly one of \"mfp\" (volume mean free path) and \"dmfp\" "
                                        "(diffuse mean free path), per color channel, in scene units");
  const Rgb length = desc.get_rgb(has_mfp ? "mfp" : "dmfp", {}, Range::positive());
  const std::string pz = desc.get_enum("parameterization", {"searchlight", "diffuse", "dmfp"},
                                       has_dmfp ? "dmfp" : "searchlight");
  if ((pz == "dmfp") != has_dmfp)
    desc.fail("parameterization", has_dmfp ? "\"" + pz + "\" is a parameterization of the mean free path: use \"mfp\""
                                           : "\"dmfp\" needs the \"dmfp\" key instead of \"mfp\"");
  const SubsurfaceParameterization p = pz == "dmfp"      ? SubsurfaceParameterization::Dmfp
                                       : pz == "diffuse" ? SubsurfaceParameterization::Diffuse
                                                         : SubsurfaceParameterization::Searchlight;
  const float ior = desc.get_float("ior", 1.4f, Range::positive());
  const std::optional<RoughnessSpec> rough = read_roughness(desc);
  const std::string ms = desc.get_enum("multiscatter", {"none", "compensated"}, "compensated");
  const bool smooth = !rough || rough->smooth();
  return std::make_unique<SubsurfaceMaterial>(
      albedo, length, p, ior, smooth, smooth ? MicrofacetDistribution() : rough->distribution(),
      ms == "compensated" ? MultiscatterMode::Compensated : MultiscatterMode::None);
}

const Bsdf* SubsurfaceMaterial::bsdf(const SurfaceInteraction& si, Arena& arena) const {
  return arena.make<SubsurfaceBoundaryBsdf>(boundary_.bsdf(si, arena));
}

}  // namespace kozu
