#include "materials/dielectric.h"

#include "core/json_reader.h"
#include "materials/fresnel.h"
#include "materials/microsurface_walk.h"
#include "materials/roughness.h"

namespace kozu {

BsdfSample SmoothDielectricBsdf::sample(const Vec3& wo, float u_lobe, const Vec2&, TransportMode mode) const {
  BsdfSample s;
  const float cos_o = cos_theta(wo);
  if (cos_o == 0.0f) return s;
  const float r = fresnel_dielectric(cos_o, eta_);  // F (fresnel.h, Born & Wolf §1.5)
  const float t = 1.0f - r;
  if (u_lobe < r) {
    s.wi = Vec3(-wo.x, -wo.y, wo.z);
    s.f = Rgb(r);
    s.pdf = r;
    s.flags = kBsdfReflection | kBsdfSpecular;
    return s;
  }
  // Relative IOR from wo's side to the other side.
  const bool outside = cos_o > 0.0f;
  const float eta = outside ? eta_ : 1.0f / eta_;
  Vec3 wi;
  if (!refract(wo, Vec3(0.0f, 0.0f, outside ? 1.0f : -1.0f), eta, &wi)) return s;  // unreachable: TIR has r = 1
  float ft = t;
  if (mode == TransportMode::Radiance) ft /= eta * eta;  // radiance scaling (bsdf.h; Veach 1997 §5.2)
  s.wi = wi;
  s.f = Rgb(ft);
  s.pdf = t;
  s.flags = kBsdfTransmission | kBsdfSpecular;
  s.eta = eta;
  return s;
}

// ---- rough ------------------------------------------------------------------------------------------

namespace {

// The configuration seen from wo's side: wo mirrored to +z, and the relative IOR across the interface.
struct Oriented {
  Vec3 wo, wi;
  float eta;  // IOR of the -z side over the +z side
  int side;   // 0: wo outside, 1: wo inside
};

Oriented orient(const Vec3& wo, const Vec3& wi, float eta) {
  if (wo.z >= 0.0f) return {wo, wi, eta, 0};
  return {Vec3(wo.x, wo.y, -wo.z), Vec3(wi.x, wi.y, -wi.z), 1.0f / eta, 1};
}

}  // namespace

Rgb RoughDielectricBsdf::eval_pdf(const Vec3& wo_in, const Vec3& wi_in, float* pdf_out, TransportMode mode) const {
  *pdf_out = 0.0f;
  const Oriented o = orient(wo_in, wi_in, eta_);
  const Vec3& wo = o.wo;
  const Vec3& wi = o.wi;
  if (wo.z <= 0.0f || wi.z == 0.0f) return Rgb(0.0f);
  const bool reflect_lobe = wi.z > 0.0f;
  // Single scattering, zero unless a microfacet joins wo and wi. (Only this term: the compensation lobe
  // below covers both hemispheres whole, including the transmitted directions no single refraction reaches.)
  float f = 0.0f, p = 0.0f;
  Vec3 h = reflect_lobe ? wo + wi : wo + o.eta * wi;  // Walter eq. 16 for refraction
  const float len = glm::length(h);
  h = len > 0.0f ? h / len : Vec3(0.0f);
  if (h.z < 0.0f) h = -h;
  const float cos_oh = glm::dot(wo, h), cos_ih = glm::dot(wi, h);
  // The microfacet must face wo, and for refraction wi must leave through its back.
  if (len > 0.0f && cos_oh > 0.0f && (reflect_lobe ? cos_ih > 0.0f : cos_ih < 0.0f)) {
    const float F = fresnel_dielectric(cos_oh, o.eta);
    const float D = d_.D(h);
    const float lambda_o = d_.lambda(wo);
    const float G2 = 1.0f / (1.0f + lambda_o + d_.lambda(wi));  // height-correlated (Heitz 2014; microfacet.h)
    const float vndf = D / ((1.0f + lambda_o) * wo.z);          // D_wo(h) / (wo·h), Heitz & d'Eon 2014 eq. (2)
    if (reflect_lobe) {
      f = F * D * G2 / (4.0f * wo.z);  // Walter eq. (20), times cos θi
      p = F * vndf / 4.0f;
    } else {
      const float denom = cos_ih + cos_oh / o.eta;
      const float jacobian = std::abs(cos_ih) / (denom * denom);  // dωh/dωi (Walter eq. 17)
      f = (1.0f - F) * D * G2 * cos_oh * jacobian / wo.z;         // Walter eq. (21), times cos θi
      if (mode == TransportMode::Radiance) f /= o.eta * o.eta;
      p = (1.0f - F) * vndf * cos_oh * jacobian;
    }
  }
  if (!comp_) {
    *pdf_out = p;
    return Rgb(f);
  }
  // Coupled compensation lobe (see the header).
  const int s = o.side;
  const float e_o = comp_->e[s].eval(wo.z);
  const float mu_i = std::abs(wi.z);
  float f_ms, p_ms;
  if (reflect_lobe) {  // same side: r_s (1 − E_s(μi)) / (π (1 − Ē_s)), r_s = 1 − t_s
    const float share = 1.0f - comp_->t[s];
    f_ms = share * comp_->lobe[s].shape(mu_i);
    p_ms = share * comp_->lobe[s].pdf(mu_i);
  } else {  // other side: t_s (1 − E_s̄(μi)) / (π (1 − Ē_s̄))
    const float share = comp_->t[s];
    f_ms = share * comp_->lobe[1 - s].shape(mu_i);
    if (mode == TransportMode::Radiance) f_ms /= o.eta * o.eta;
    p_ms = share * comp_->lobe[1 - s].pdf(mu_i);
  }
  *pdf_out = e_o * p + (1.0f - e_o) * p_ms;
  return Rgb(f + (1.0f - e_o) * f_ms * mu_i);  // f_ms cos θi = (1 − E_s(μo)) · {…}: the header's compensation
}

BsdfSample RoughDielectricBsdf::sample(const Vec3& wo_in, float u_lobe, const Vec2& u, TransportMode mode) const {
  BsdfSample s;
  if (wo_in.z == 0.0f) return s;
  const Oriented o = orient(wo_in, Vec3(0.0f), eta_);
  const Vec3& wo = o.wo;
  Vec3 wi;
  const float e_o = comp_ ? comp_->e[o.side].eval(wo.z) : 1.0f;
  if (u_lobe < e_o) {
    // Single scattering: a visible normal, then reflection with probability F.
    u_lobe /= e_o;
    const Vec3 m = d_.sample_visible(wo, u);
    const float cos_om = glm::dot(wo, m);
    if (cos_om <= 0.0f) return s;
    const float F = fresnel_dielectric(cos_om, o.eta);
    if (u_lobe < F) {
      wi = reflect(wo, m);
      if (wi.z <= 0.0f) return s;
    } else {
      if (!refract(wo, m, o.eta, &wi) || wi.z >= 0.0f) return s;
    }
  } else {
    // The compensation lobe: reflected or transmitted by its shares.
    const float v = (u_lobe - e_o) / (1.0f - e_o);
    const bool transmit = v < comp_->t[o.side];
    float p;
    wi = comp_->lobe[transmit ? 1 - o.side : o.side].sample(u, &p);
    if (transmit) wi.z = -wi.z;
  }
  if (o.side == 1) wi.z = -wi.z;
  const bool transmitted = wi.z * wo_in.z < 0.0f;
  return sample_at(wo_in, wi, (transmitted ? kBsdfTransmission : kBsdfReflection) | kBsdfGlossy, mode,
                   transmitted ? o.eta : 1.0f);
}

// ---- stochastic (Heitz et al. 2016) --------------------------------------------------------------------

namespace {
// Salt of the walk's generator (walk_rng).
constexpr uint64_t kDielectricSalt = 0x4f1bbcdcbfa53e0bull;
// Share of the cosine lobes (one per side) in the proxy pdf.
constexpr float kProxyCosine = 0.2f;
}  // namespace

Rgb StochasticDielectricBsdf::eval(const Vec3& wo, const Vec3& wi, TransportMode mode) const {
  Pcg32 rng = walk_rng(wo, wi, kDielectricSalt);
  return Rgb(MicrosurfaceWalk(d_).eval_dielectric(wo, wi, eta_, mode, rng));
}

float StochasticDielectricBsdf::pdf(const Vec3& wo, const Vec3& wi) const {
  if (wo.z == 0.0f || wi.z == 0.0f) return 0.0f;
  const RoughDielectricBsdf single(d_, eta_, nullptr);
  return (1.0f - kProxyCosine) * single.pdf(wo, wi) + 0.5f * kProxyCosine * abs_cos_theta(wi) * kInvPi;
}

BsdfSample StochasticDielectricBsdf::sample(const Vec3& wo, float u_lobe, const Vec2& u, TransportMode mode) const {
  BsdfSample s;
  if (wo.z == 0.0f) return s;
  Pcg32 rng = walk_rng(wo, Vec3(u_lobe, u.x, u.y), kDielectricSalt);
  Vec3 wi;
  float weight;
  if (!MicrosurfaceWalk(d_).sample_dielectric(wo, eta_, mode, rng, &wi, &weight)) return s;
  s.pdf = pdf(wo, wi);
  if (!(s.pdf > 0.0f)) {
    s.pdf = 0.0f;
    return s;
  }
  s.wi = wi;
  s.f = Rgb(weight * s.pdf);  // f / pdf is the walk's weight (see StochasticConductorBsdf)
  const bool transmitted = wi.z * wo.z < 0.0f;
  s.flags = (transmitted ? kBsdfTransmission : kBsdfReflection) | kBsdfGlossy;
  s.eta = transmitted ? (wo.z > 0.0f ? eta_ : 1.0f / eta_) : 1.0f;
  return s;
}

// ---- material -----------------------------------------------------------------------------------------

DielectricCompensation DielectricCompensation::make(MicrofacetType type, float alpha, float ior) {
  DielectricCompensation comp;
  const float eta_side[2] = {ior, 1.0f / ior};  // relative IOR seen from outside / inside
  // E_s(μ): the single-scattering reflection + transmission albedo seen from side s (the header's compensation).
  for (int s = 0; s < 2; ++s) {
    comp.e[s] = AlbedoCurve([&](float mu) { return albedo::dielectric_E(type, mu, alpha, eta_side[s]); });
    comp.lobe[s] = CoupledLobe(comp.e[s]);
  }
  // Side a faces the denser medium (η_a ≥ 1). Its transmitted share is the smooth interface's
  // hemispherical transmittance 1 − F_avg(η_a) (F_avg of ushiostarfish 2018), capped so that reciprocity's t_b stays
  // ≤ 1.
  const int a = ior >= 1.0f ? 0 : 1, b = 1 - a;
  const float eta_a = eta_side[a];
  const float loss_a = 1.0f - comp.e[a].average(), loss_b = 1.0f - comp.e[b].average();
  if (loss_a > 1e-6f && loss_b > 1e-6f) {
    const float f_avg = albedo::fresnel_average([&](float mu) { return fresnel_dielectric(mu, eta_a); });
    const float t_a = std::min(1.0f - f_avg, eta_a * eta_a * loss_b / loss_a);
    comp.t[a] = t_a;
    comp.t[b] = std::min(1.0f, t_a * loss_a / (eta_a * eta_a * loss_b));  // t_s̄ = t_s (1 − Ē_s) / (η_s² (1 − Ē_s̄))
  }
  return comp;
}

DielectricMaterial::DielectricMaterial(float ior, bool smooth, const MicrofacetDistribution& d, MultiscatterMode mode)
    : ior_(ior), smooth_(smooth || index_matched(ior)), d_(d), mode_(mode) {
  if (smooth_ || mode_ != MultiscatterMode::Compensated) return;
  comp_ = DielectricCompensation::make(d_.type(), d_.effective_alpha(), ior_);
}

DielectricMaterial::DielectricMaterial(float ior, std::unique_ptr<const TexturedRoughness> roughness,
                                       MultiscatterMode mode)
    : ior_(ior),
      smooth_(index_matched(ior)),
      mode_(mode),
      rough_tex_(std::move(roughness)),
      tex_comp_(!smooth_ && mode == MultiscatterMode::Compensated ? rough_tex_->constant_key() : std::nullopt,
                [this](float key) {
                  return DielectricCompensation::make(rough_tex_->type(), rough_tex_->table_alpha(key), ior_);
                }) {}

MicrofacetDistribution DielectricMaterial::distribution_at(const SurfaceInteraction& si,
                                                           const DielectricCompensation** comp) const {
  const bool compensated = mode_ == MultiscatterMode::Compensated;
  if (!rough_tex_) {
    *comp = compensated ? &comp_ : nullptr;
    return d_;
  }
  float key;
  const MicrofacetDistribution d = rough_tex_->at(texture_query(si), &key);
  *comp = compensated ? &tex_comp_.at(key) : nullptr;
  return d;
}

float DielectricMaterial::table_key_at(const SurfaceInteraction& si) const {
  if (!rough_tex_) return 0.0f;
  float key;
  rough_tex_->at(texture_query(si), &key);
  return key;
}

RoughDielectricBsdf DielectricMaterial::level_bsdf(float key) const {
  return RoughDielectricBsdf(rough_tex_->table_distribution(key), ior_,
                             mode_ == MultiscatterMode::Compensated ? &tex_comp_.at(key) : nullptr);
}

Deferred<Material> DielectricMaterial::parse(const JsonObject& desc, const MaterialParseContext& ctx) {
  const float ior = desc.get_float("ior", 1.5f, Range::positive());
  const std::optional<RoughnessTextureDesc> rough_textures = read_roughness_textures(desc, ctx.textures);
  std::optional<RoughnessSpec> rough;
  if (!rough_textures) rough = read_roughness(desc);
  const MultiscatterMode mode = read_multiscatter(desc);
  if (rough_textures) {
    if (mode == MultiscatterMode::Stochastic && index_matched(ior))
      desc.fail("multiscatter",
                "\"stochastic\" needs an ior different from 1 (an index-matched interface does not scatter)");
    const auto rough_tex = std::make_shared<RoughnessTextureDesc>(*rough_textures);
    return Deferred<Material>([ior, rough_tex, mode]() -> std::unique_ptr<Material> {
      return std::make_unique<DielectricMaterial>(ior, rough_tex->build(), mode);
    });
  }
  const bool smooth = !rough || rough->smooth();
  if (smooth && mode != MultiscatterMode::None)
    desc.warn("multiscatter",
              "has no effect on a smooth dielectric (it reflects or refracts once); give it a roughness");
  // The random walk refracts through every facet: at ior 1 refraction is a Dirac delta it cannot sample.
  if (!smooth && mode == MultiscatterMode::Stochastic && index_matched(ior))
    desc.fail("multiscatter",
              "\"stochastic\" needs an ior different from 1 (an index-matched interface does not scatter)");
  return std::make_unique<DielectricMaterial>(ior, smooth, smooth ? MicrofacetDistribution() : rough->distribution(),
                                              mode);
}

const Bsdf* DielectricMaterial::bsdf(const SurfaceInteraction& si, Arena& arena) const {
  if (smooth_) return arena.make<SmoothDielectricBsdf>(ior_);
  if (rough_tex_) {
    const DielectricCompensation* comp;
    const MicrofacetDistribution d = distribution_at(si, &comp);
    if (mode_ == MultiscatterMode::Stochastic) return arena.make<StochasticDielectricBsdf>(d, ior_);
    return arena.make<RoughDielectricBsdf>(d, ior_, comp);
  }
  if (mode_ == MultiscatterMode::Stochastic) return arena.make<StochasticDielectricBsdf>(d_, ior_);
  return arena.make<RoughDielectricBsdf>(d_, ior_, mode_ == MultiscatterMode::Compensated ? &comp_ : nullptr);
}

}  // namespace kozu
