#include "materials/plastic.h"

#include "core/json_reader.h"
#include "materials/fresnel.h"
#include "materials/ltc_table.h"
#include "materials/roughness.h"
#include "textures/texture_parse.h"

namespace kozu {

// ushiostarfish 2018 P_spec = E_R(μo) / (E_R(μo) + k̃ (1 − E_R(μo))), k̃ the mean of k.
float PlasticBsdf::spec_probability(float e_o) const {
  const float k_mean = (k_.r + k_.g + k_.b) / 3.0f;
  const float denom = e_o + k_mean * (1.0f - e_o);
  return denom > 0.0f ? e_o / denom : 1.0f;
}

Rgb PlasticBsdf::eval_pdf(const Vec3& wo_in, const Vec3& wi_in, float* pdf_out, TransportMode) const {
  *pdf_out = 0.0f;
  // Two-sided, like diffuse: mirror a configuration seen from below.
  const float flip = wo_in.z < 0.0f ? -1.0f : 1.0f;
  const Vec3 wo(wo_in.x, wo_in.y, wo_in.z * flip), wi(wi_in.x, wi_in.y, wi_in.z * flip);
  if (wo.z <= 0.0f || wi.z <= 0.0f) return Rgb(0.0f);
  const float e_o = tables_->e_r.eval(wo.z);
  const float p_spec_lobe = spec_probability(e_o);
  // ushiostarfish 2018 f_matte = k (1 − E_R(μi)) (1 − E_R(μo)) / (π (1 − E_R,avg)), times cos θi
  Rgb f = k_ * ((1.0f - e_o) * tables_->lobe.shape(wi.z) * wi.z);
  float p = (1.0f - p_spec_lobe) * tables_->lobe.pdf(wi.z);
  if (!smooth_) {
    Vec3 h = wo + wi;
    const float len = glm::length(h);
    if (len > 0.0f) {
      h /= len;
      const float D = d_.D(h);
      const float lambda_o = d_.lambda(wo);
      const float F = fresnel_dielectric(glm::dot(wo, h), eta_);
      f += Rgb(F * D / ((1.0f + lambda_o + d_.lambda(wi)) * 4.0f * wo.z));  // ushiostarfish 2018 f_spec, times cos θi
      p += p_spec_lobe * D / (4.0f * (1.0f + lambda_o) * wo.z);             // VNDF, Heitz & d'Eon 2014 eq. (2)
    }
  }
  *pdf_out = p;
  return f;
}

BsdfSample PlasticBsdf::sample(const Vec3& wo_in, float u_lobe, const Vec2& u, TransportMode mode) const {
  BsdfSample s;
  if (wo_in.z == 0.0f) return s;
  const float flip = wo_in.z < 0.0f ? -1.0f : 1.0f;
  const Vec3 wo(wo_in.x, wo_in.y, wo_in.z * flip);
  const float p_spec_lobe = spec_probability(tables_->e_r.eval(wo.z));
  Vec3 wi;
  if (u_lobe < p_spec_lobe) {
    if (smooth_) {
      s.wi = Vec3(-wo_in.x, -wo_in.y, wo_in.z);
      s.f = Rgb(fresnel_dielectric(wo.z, eta_));
      s.pdf = p_spec_lobe;
      s.flags = kBsdfReflection | kBsdfSpecular;
      return s;
    }
    wi = reflect(wo, d_.sample_visible(wo, u));
  } else {
    float p;
    wi = tables_->lobe.sample(u, &p);  // ∝ (1 − E_R(μi)) cos θi (ushiostarfish 2018, CoupledLobe)
  }
  if (wi.z <= 0.0f) return s;
  wi.z *= flip;
  return sample_at(wo_in, wi, kBsdfReflection | (u_lobe < p_spec_lobe ? kBsdfGlossy : kBsdfDiffuse), mode);
}

int PlasticBsdf::ltc_lobes(const Vec3& wo, const Vec3&, LtcLobe* out) const {
  if (!(wo.z > 0.0f)) return 0;
  const float e_o = tables_->e_r.eval(wo.z);
  int n = 0;
  if (!smooth_) {
    const LtcBrdf brdf = d_.type() == MicrofacetType::GGX ? LtcBrdf::GgxSpecular : LtcBrdf::BeckmannSpecular;
    out[n++] = LtcLobe{ltc_lobe(brdf, wo, std::sqrt(d_.alpha_x() * d_.alpha_y())).ltc, Rgb(e_o)};
  }
  out[n++] = LtcLobe{Ltc(), k_ * (1.0f - e_o)};
  return n;
}

PlasticTables PlasticTables::make_rough(MicrofacetType type, float alpha, float ior) {
  PlasticTables t;
  // ushiostarfish 2018 E_R(μ) = ∫ f_spec cos θi dωi, baked with the dielectric Fresnel (microfacet_albedo.h).
  t.e_r = AlbedoCurve([&](float mu) { return albedo::dielectric_ER(type, mu, alpha, ior); });
  t.lobe = CoupledLobe(t.e_r);
  return t;
}

PlasticMaterial::PlasticMaterial(const Rgb& k, float ior, bool smooth, const MicrofacetDistribution& d)
    : PlasticMaterial(k, ior, smooth, d, Textures{}) {}

PlasticMaterial::PlasticMaterial(const Rgb& k, float ior, bool smooth, const MicrofacetDistribution& d,
                                 Textures textures)
    : k_(k),
      ior_(ior),
      smooth_(smooth && !textures.roughness),
      d_(d),
      rough_tex_(std::move(textures.roughness)),
      tex_tables_(rough_tex_ ? rough_tex_->constant_key() : std::nullopt,
                  [this](float key) {
                    return PlasticTables::make_rough(rough_tex_->type(), rough_tex_->table_alpha(key), ior_);
                  }),
      albedo_tex_(std::move(textures.albedo)) {
  if (rough_tex_) return;
  if (smooth_) {
    tables_.e_r = AlbedoCurve([&](float mu) { return fresnel_dielectric(mu, ior_); });  // E_R(μ) = F(μ)
    tables_.lobe = CoupledLobe(tables_.e_r);
  } else {
    tables_ = PlasticTables::make_rough(d_.type(), d_.effective_alpha(), ior_);
  }
}

Deferred<Material> PlasticMaterial::parse(const JsonObject& desc, const MaterialParseContext& ctx) {
  std::shared_ptr<Deferred<Texture>> albedo_tex;
  Rgb k(0.5f);
  if (desc.has("albedo") && desc.raw("albedo").is_object())
    albedo_tex = std::make_shared<Deferred<Texture>>(
        parse_texture(desc, "albedo", {TextureUse::Color, ctx.textures, Range::unit()}));
  else
    k = desc.get_rgb("albedo", Rgb(0.5f), Range::unit());
  const float ior = desc.get_float("ior", 1.5f, Range::at_least(1.0));
  const std::optional<RoughnessTextureDesc> rough_textures = read_roughness_textures(desc, ctx.textures);
  std::optional<RoughnessSpec> rough;
  if (!rough_textures) {
    rough = read_roughness(desc);
    if (!rough) {
      rough = RoughnessSpec{};
      rough->alpha_x = rough->alpha_y = 0.09f;  // roughness 0.3
    }
  }
  const bool smooth = !rough_textures && rough->smooth();
  const MicrofacetDistribution d = smooth || rough_textures ? MicrofacetDistribution() : rough->distribution();
  if (!albedo_tex && !rough_textures) return std::make_unique<PlasticMaterial>(k, ior, smooth, d);
  const auto rough_tex = rough_textures ? std::make_shared<RoughnessTextureDesc>(*rough_textures) : nullptr;
  return Deferred<Material>([=]() -> std::unique_ptr<Material> {
    Textures t;
    if (albedo_tex) t.albedo = albedo_tex->take();
    if (rough_tex) t.roughness = rough_tex->build();
    return std::make_unique<PlasticMaterial>(k, ior, smooth, d, std::move(t));
  });
}

const Bsdf* PlasticMaterial::bsdf(const SurfaceInteraction& si, Arena& arena) const {
  if (!albedo_tex_ && !rough_tex_) return arena.make<PlasticBsdf>(d_, smooth_, ior_, k_, &tables_);
  const TextureQuery q = texture_query(si);
  const Rgb k = albedo_tex_ ? glm::clamp(albedo_tex_->eval(q), Rgb(0.0f), Rgb(1.0f)) : k_;
  if (!rough_tex_) return arena.make<PlasticBsdf>(d_, smooth_, ior_, k, &tables_);
  float key;
  const MicrofacetDistribution d = rough_tex_->at(q, &key);
  return arena.make<PlasticBsdf>(d, false, ior_, k, &tex_tables_.at(key));
}

}  // namespace kozu
