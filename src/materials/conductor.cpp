#include "materials/conductor.h"

#include "core/json_reader.h"
#include "core/rng.h"
#include "materials/fresnel.h"
#include "materials/ltc_table.h"
#include "materials/metal_data.h"
#include "materials/microsurface_walk.h"
#include "materials/roughness.h"
#include "textures/texture_parse.h"

#include <fmt/format.h>

namespace kozu {

BsdfSample SmoothConductorBsdf::sample(const Vec3& wo, float, const Vec2&, TransportMode) const {
  BsdfSample s;
  if (wo.z == 0.0f) return s;
  s.wi = Vec3(-wo.x, -wo.y, wo.z);
  s.f = fresnel_->eval(abs_cos_theta(wo));  // F(n, k, θ), fresnel.h
  s.pdf = 1.0f;
  s.flags = kBsdfReflection | kBsdfSpecular;
  return s;
}

// ---- rough, single scattering + compensation ----------------------------------------------------

Rgb RoughConductorBsdf::eval_pdf(const Vec3& wo_in, const Vec3& wi_in, float* pdf_out, TransportMode) const {
  *pdf_out = 0.0f;
  // Two-sided: mirror a configuration seen from below.
  const float flip = wo_in.z < 0.0f ? -1.0f : 1.0f;
  const Vec3 wo(wo_in.x, wo_in.y, wo_in.z * flip), wi(wi_in.x, wi_in.y, wi_in.z * flip);
  if (wo.z <= 0.0f || wi.z <= 0.0f) return Rgb(0.0f);
  Vec3 h = wo + wi;
  const float len = glm::length(h);
  if (len == 0.0f) return Rgb(0.0f);
  h /= len;
  const float cos_oh = glm::dot(wo, h);
  const float D = d_.D(h);
  const float lambda_o = d_.lambda(wo), lambda_i = d_.lambda(wi);
  // f cos θi = F D G2 / (4 cos θo): ushiostarfish 2018 f_spec, with the height-correlated G2 (microfacet.h)
  Rgb f = fresnel_->eval(cos_oh) * (D / ((1.0f + lambda_o + lambda_i) * 4.0f * wo.z));
  // VNDF pdf of wi: D_wo(h) / (4 wo·h) = D / (4 (1 + Λo) cos θo) (Heitz & d'Eon 2014 eq. (2), microfacet.h)
  const float p_spec = D / (4.0f * (1.0f + lambda_o) * wo.z);
  if (!comp_) {
    *pdf_out = p_spec;
    return f;
  }
  const float e_o = comp_->e.eval(wo.z);
  f += f_ms_ * ((1.0f - e_o) * comp_->lobe.shape(wi.z) * wi.z);  // ushiostarfish 2018 f_ms, the coupled lobe
  *pdf_out =
      e_o * p_spec + (1.0f - e_o) * comp_->lobe.pdf(wi.z);  // ushiostarfish 2018 P_spec = E(μo), P_ms = 1 − E(μo)
  return f;
}

LtcLobe conductor_ltc_lobe(MicrofacetType type, const Vec3& wo, float alpha, const Rgb& f0, bool compensated,
                           const Rgb& coupled, Rgb* cosine) {
  const bool ggx = type == MicrofacetType::GGX;
  const LtcBrdf single = ggx ? LtcBrdf::Ggx : LtcBrdf::Beckmann;
  if (compensated && alpha >= kLtcCompensatedMinAlpha) {
    const LtcLobeFit fit = ltc_lobe(ggx ? LtcBrdf::GgxCompensated : LtcBrdf::BeckmannCompensated, wo, alpha);
    float norm, fresnel_norm;
    ltc_norms(single, wo.z, alpha, &norm, &fresnel_norm);
    return LtcLobe{fit.ltc, f0 * norm + (Rgb(1.0f) - f0) * fresnel_norm + coupled};
  }
  const LtcLobeFit fit = ltc_lobe(single, wo, alpha);
  *cosine += coupled;
  return LtcLobe{fit.ltc, f0 * fit.norm + (Rgb(1.0f) - f0) * fit.fresnel_norm};
}

int RoughConductorBsdf::ltc_lobes(const Vec3& wo, const Vec3&, LtcLobe* out) const {
  if (!(wo.z > 0.0f)) return 0;
  const Rgb coupled = comp_ ? f_ms_ * (1.0f - comp_->e.eval(wo.z)) : Rgb(0.0f);
  Rgb cosine(0.0f);
  const float alpha = std::sqrt(d_.alpha_x() * d_.alpha_y());
  out[0] = conductor_ltc_lobe(d_.type(), wo, alpha, fresnel_->eval(1.0f), comp_ != nullptr, coupled, &cosine);
  if (!comp_ || alpha >= kLtcCompensatedMinAlpha) return 1;
  out[1] = LtcLobe{Ltc(), cosine};
  return 2;
}

Rgb RoughConductorBsdf::eval(const Vec3& wo, const Vec3& wi, TransportMode mode) const {
  float p;
  return eval_pdf(wo, wi, &p, mode);
}

// The pdf alone skips the Fresnel term and Λ(wi) (same expressions as eval_pdf, so the same bits).
float RoughConductorBsdf::pdf(const Vec3& wo_in, const Vec3& wi_in) const {
  const float flip = wo_in.z < 0.0f ? -1.0f : 1.0f;
  const Vec3 wo(wo_in.x, wo_in.y, wo_in.z * flip), wi(wi_in.x, wi_in.y, wi_in.z * flip);
  if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
  Vec3 h = wo + wi;
  const float len = glm::length(h);
  if (len == 0.0f) return 0.0f;
  h /= len;
  const float p_spec = d_.D(h) / (4.0f * (1.0f + d_.lambda(wo)) * wo.z);  // Heitz & d'Eon 2014 eq. (2)
  if (!comp_) return p_spec;
  const float e_o = comp_->e.eval(wo.z);
  return e_o * p_spec + (1.0f - e_o) * comp_->lobe.pdf(wi.z);  // ushiostarfish 2018 P_spec, P_ms
}

BsdfSample RoughConductorBsdf::sample(const Vec3& wo_in, float u_lobe, const Vec2& u, TransportMode mode) const {
  BsdfSample s;
  if (wo_in.z == 0.0f) return s;
  const float flip = wo_in.z < 0.0f ? -1.0f : 1.0f;
  const Vec3 wo(wo_in.x, wo_in.y, wo_in.z * flip);
  Vec3 wi;
  // Lobe choice with P_spec = E(μo) (ushiostarfish 2018, conductor case).
  if (comp_ && u_lobe >= comp_->e.eval(wo.z)) {
    float p;
    wi = comp_->lobe.sample(u, &p);
  } else {
    const Vec3 m = d_.sample_visible(wo, u);
    wi = reflect(wo, m);
  }
  if (wi.z <= 0.0f) return s;
  wi.z *= flip;
  return sample_at(wo_in, wi, kBsdfReflection | kBsdfGlossy, mode);
}

// ---- stochastic (Heitz et al. 2016) --------------------------------------------------------------

namespace {
// Salt of the walk's generator (walk_rng).
constexpr uint64_t kConductorSalt = 0x2545f4914f6cdd1dull;
// Share of the cosine lobe in the proxy pdf: keeps it positive wherever the walk can exit.
constexpr float kProxyCosine = 0.2f;
}  // namespace

Rgb StochasticConductorBsdf::eval(const Vec3& wo, const Vec3& wi, TransportMode) const {
  Pcg32 rng = walk_rng(wo, wi, kConductorSalt);
  return MicrosurfaceWalk(d_).eval_conductor(wo, wi, *fresnel_, rng);
}

float StochasticConductorBsdf::pdf(const Vec3& wo, const Vec3& wi) const {
  if (!same_hemisphere(wo, wi)) return 0.0f;
  const RoughConductorBsdf single(d_, fresnel_, nullptr);
  return (1.0f - kProxyCosine) * single.pdf(wo, wi) + kProxyCosine * abs_cos_theta(wi) * kInvPi;
}

BsdfSample StochasticConductorBsdf::sample(const Vec3& wo, float u_lobe, const Vec2& u, TransportMode) const {
  BsdfSample s;
  if (wo.z == 0.0f) return s;
  Pcg32 rng = walk_rng(wo, Vec3(u_lobe, u.x, u.y), kConductorSalt);
  Vec3 wi;
  Rgb weight;
  if (!MicrosurfaceWalk(d_).sample_conductor(wo, *fresnel_, rng, &wi, &weight)) return s;
  s.pdf = pdf(wo, wi);
  if (!(s.pdf > 0.0f)) {
    s.pdf = 0.0f;
    return s;
  }
  // The walk's weight is f cos θi / p_walk; reporting the proxy pdf keeps f / pdf equal to it.
  s.wi = wi;
  s.f = weight * s.pdf;
  s.flags = kBsdfReflection | kBsdfGlossy;
  return s;
}

// ---- material -------------------------------------------------------------------------------------

MultiscatterMode read_multiscatter(const JsonObject& desc) {
  const std::string m = desc.get_enum("multiscatter", {"none", "compensated", "stochastic"}, "none");
  if (m == "compensated") return MultiscatterMode::Compensated;
  if (m == "stochastic") return MultiscatterMode::Stochastic;
  return MultiscatterMode::None;
}

ConductorCompensation ConductorCompensation::make(MicrofacetType type, float alpha, const ConductorFresnel& fresnel,
                                                  bool series) {
  ConductorCompensation comp;
  comp.e = AlbedoCurve(
      [&](float mu) { return albedo::conductor_E(type, mu, alpha); });  // ushiostarfish 2018 E(μ) = a_spec(θ)
  comp.lobe = CoupledLobe(comp.e);
  const Rgb f_avg = albedo::fresnel_average([&](float mu) { return fresnel.eval(mu); });  // ushiostarfish 2018 F_avg
  comp.f_ms = multiple_fresnel(f_avg, comp.e.average(), series);
  return comp;
}

Rgb ConductorCompensation::multiple_fresnel(const Rgb& f_avg, float e_avg, bool series) {
  // Kulla–Conty: the energy of the 2nd, 3rd, ... bounces, each attenuated by F_avg (ushiostarfish 2018).
  if (series) return f_avg * f_avg * e_avg / (Rgb(1.0f) - f_avg * (1.0f - e_avg));  // F_ms, "series"
  return f_avg;  // F_ms = F_avg, "average" (ushiostarfish 2018's choice)
}

ConductorMaterial::ConductorMaterial(const ConductorFresnel& fresnel, bool smooth, const MicrofacetDistribution& d,
                                     MultiscatterMode mode, bool series_fresnel)
    : ConductorMaterial(fresnel, smooth, d, mode, series_fresnel, Textures{}) {}

ConductorMaterial::ConductorMaterial(const ConductorFresnel& fresnel, bool smooth, const MicrofacetDistribution& d,
                                     MultiscatterMode mode, bool series_fresnel, Textures textures)
    : fresnel_(fresnel),
      smooth_(smooth && !textures.roughness),
      d_(d),
      mode_(mode),
      series_(series_fresnel),
      rough_tex_(std::move(textures.roughness)),
      tex_comp_(rough_tex_ && mode == MultiscatterMode::Compensated ? rough_tex_->constant_key() : std::nullopt,
                [this](float key) {
                  return ConductorCompensation::make(rough_tex_->type(), rough_tex_->table_alpha(key), fresnel_,
                                                     series_);
                }),
      eta_tex_(std::move(textures.eta)),
      k_tex_(std::move(textures.k)) {
  if (smooth_ || rough_tex_ || mode_ != MultiscatterMode::Compensated) return;
  comp_ = ConductorCompensation::make(d_.type(), d_.effective_alpha(), fresnel_, series_);
}

Deferred<Material> ConductorMaterial::parse(const JsonObject& desc, const MaterialParseContext& ctx) {
  ConductorFresnel fresnel;
  const bool has_metal = desc.has("metal");
  const bool has_eta = desc.has("eta") || desc.has("k");
  if (has_metal && has_eta) desc.fail("metal", "give either 'metal' or 'eta'/'k', not both");
  // eta and k: optical constants, read as data (see the header).
  const auto texture = [&](const char* key, const Range& range) -> std::shared_ptr<Deferred<Texture>> {
    if (!desc.has(key) || !desc.raw(key).is_object()) return nullptr;
    return std::make_shared<Deferred<Texture>>(parse_texture(desc, key, {TextureUse::Data, ctx.textures, range}));
  };
  std::shared_ptr<Deferred<Texture>> eta_tex, k_tex;
  if (has_metal) {
    const std::string name = desc.get_string("metal");
    const MetalIor* m = find_metal(name);
    if (!m) {
      std::string list;
      for (const auto& e : kMetals) list += (list.empty() ? "" : ", ") + std::string(e.symbol);
      desc.fail("metal", fmt::format("unknown metal '{}' (known: {})", name, list));
    }
    fresnel.eta = m->eta;
    fresnel.k = m->k;
    fresnel.perfect = false;
  } else if (has_eta) {
    eta_tex = texture("eta", Range::positive());
    if (!eta_tex) fresnel.eta = desc.get_rgb("eta", {}, Range::positive());
    k_tex = texture("k", Range::non_negative());
    if (!k_tex) fresnel.k = desc.get_rgb("k", Rgb(0.0f), Range::non_negative());
    fresnel.perfect = false;
  }
  fresnel.approximate = desc.get_enum("fresnel", {"exact", "approximate"}, "exact") == "approximate";

  const std::optional<RoughnessTextureDesc> rough_textures = read_roughness_textures(desc, ctx.textures);
  std::optional<RoughnessSpec> rough;
  if (!rough_textures) rough = read_roughness(desc);
  const MultiscatterMode mode = read_multiscatter(desc);
  // "series" by default: closer to the Heitz et al. 2016 walk than F_avg
  // (RoughConductor.GoldCompensationAgainstStochastic).
  bool series = true;
  if (desc.has("ms_fresnel")) {
    if (mode != MultiscatterMode::Compensated)
      desc.fail("ms_fresnel", "applies only to \"multiscatter\": \"compensated\"");
    series = desc.get_enum("ms_fresnel", {"average", "series"}) == "series";
  }
  const bool smooth = !rough_textures && (!rough || rough->smooth());
  if (smooth && mode != MultiscatterMode::None)
    desc.warn("multiscatter", "has no effect on a smooth conductor (a mirror scatters once); give it a roughness");
  const MicrofacetDistribution d = smooth || rough_textures ? MicrofacetDistribution() : rough->distribution();
  if (!rough_textures && !eta_tex && !k_tex)
    return std::make_unique<ConductorMaterial>(fresnel, smooth, d, mode, series);
  const auto rough_tex = rough_textures ? std::make_shared<RoughnessTextureDesc>(*rough_textures) : nullptr;
  return Deferred<Material>([=]() -> std::unique_ptr<Material> {
    Textures t;
    if (rough_tex) t.roughness = rough_tex->build();
    if (eta_tex) t.eta = eta_tex->take();
    if (k_tex) t.k = k_tex->take();
    return std::make_unique<ConductorMaterial>(fresnel, smooth, d, mode, series, std::move(t));
  });
}

const Bsdf* ConductorMaterial::bsdf(const SurfaceInteraction& si, Arena& arena) const {
  const ConductorFresnel* fresnel = &fresnel_;
  const bool textured_fresnel = eta_tex_ || k_tex_;
  TextureQuery q;
  if (textured_fresnel || rough_tex_) q = texture_query(si);
  if (textured_fresnel) {
    ConductorFresnel* f = arena.make<ConductorFresnel>(fresnel_);
    if (eta_tex_) f->eta = glm::max(eta_tex_->eval(q), Rgb(1e-4f));  // eta > 0: the Fresnel term divides by it
    if (k_tex_) f->k = glm::max(k_tex_->eval(q), Rgb(0.0f));
    fresnel = f;
  }
  if (smooth_) return arena.make<SmoothConductorBsdf>(fresnel);
  MicrofacetDistribution d = d_;
  const ConductorCompensation* comp = nullptr;
  if (rough_tex_) {
    float key;
    d = rough_tex_->at(q, &key);
    if (mode_ == MultiscatterMode::Compensated) comp = &tex_comp_.at(key);
  } else if (mode_ == MultiscatterMode::Compensated) {
    comp = &comp_;
  }
  if (mode_ == MultiscatterMode::Stochastic) return arena.make<StochasticConductorBsdf>(d, fresnel);
  if (comp && textured_fresnel) {
    // F_ms of this hit's Fresnel term (ushiostarfish 2018 F_avg, F_ms).
    const Rgb f_avg = albedo::fresnel_average([&](float mu) { return fresnel->eval(mu); });
    return arena.make<RoughConductorBsdf>(d, fresnel, comp,
                                          ConductorCompensation::multiple_fresnel(f_avg, comp->e.average(), series_));
  }
  return arena.make<RoughConductorBsdf>(d, fresnel, comp);
}

}  // namespace kozu
