#include "materials/plastic.h"

#include "core/json_reader.h"
#include "materials/fresnel.h"
#include "materials/roughness.h"

namespace kozu {

// seed 002 P_spec = E_R(μo) / (E_R(μo) + k̃ (1 − E_R(μo))), k̃ the mean of k.
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
  // seed 002 f_matte = k (1 − E_R(μi)) (1 − E_R(μo)) / (π (1 − E_R,avg)), times cos θi
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
      f += Rgb(F * D / ((1.0f + lambda_o + d_.lambda(wi)) * 4.0f * wo.z));  // seed 002 f_spec, times cos θi
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
    wi = tables_->lobe.sample(u, &p);  // ∝ (1 − E_R(μi)) cos θi (seed 002, CoupledLobe)
  }
  if (wi.z <= 0.0f) return s;
  wi.z *= flip;
  return sample_at(wo_in, wi, kBsdfReflection | (u_lobe < p_spec_lobe ? kBsdfGlossy : kBsdfDiffuse), mode);
}

PlasticTables PlasticTables::make_rough(MicrofacetType type, float alpha, float ior) {
  PlasticTables t;
  // seed 002 E_R(μ) = ∫ f_spec cos θi dωi, baked with the dielectric Fresnel (microfacet_albedo.h).
  t.e_r = AlbedoCurve([&](float mu) { return albedo::dielectric_ER(type, mu, alpha, ior); });
  t.lobe = CoupledLobe(t.e_r);
  return t;
}

PlasticMaterial::PlasticMaterial(const Rgb& k, float ior, bool smooth, const MicrofacetDistribution& d)
    : k_(k), ior_(ior), smooth_(smooth), d_(d) {
  if (smooth_) {
    tables_.e_r = AlbedoCurve([&](float mu) { return fresnel_dielectric(mu, ior_); });  // E_R(μ) = F(μ)
    tables_.lobe = CoupledLobe(tables_.e_r);
  } else {
    tables_ = PlasticTables::make_rough(d_.type(), d_.effective_alpha(), ior_);
  }
}

PlasticMaterial::PlasticMaterial(const Rgb& k, float ior, std::unique_ptr<const TexturedRoughness> roughness)
    : k_(k),
      ior_(ior),
      smooth_(false),
      rough_tex_(std::move(roughness)),
      tex_tables_(rough_tex_->constant_key(), [this](float key) {
        return PlasticTables::make_rough(rough_tex_->type(), rough_tex_->table_alpha(key), ior_);
      }) {}

Deferred<Material> PlasticMaterial::parse(const JsonObject& desc, const MaterialParseContext& ctx) {
  const Rgb k = desc.get_rgb("albedo", Rgb(0.5f), Range::unit());
  const float ior = desc.get_float("ior", 1.5f, Range::at_least(1.0));
  if (std::optional<RoughnessTextureDesc> textures = read_roughness_textures(desc, ctx.textures)) {
    const auto rough_tex = std::make_shared<RoughnessTextureDesc>(std::move(*textures));
    return Deferred<Material>([k, ior, rough_tex]() -> std::unique_ptr<Material> {
      return std::make_unique<PlasticMaterial>(k, ior, rough_tex->build());
    });
  }
  std::optional<RoughnessSpec> rough = read_roughness(desc);
  if (!rough) {
    rough = RoughnessSpec{};
    rough->alpha_x = rough->alpha_y = 0.09f;  // roughness 0.3
  }
  const bool smooth = rough->smooth();
  return std::make_unique<PlasticMaterial>(k, ior, smooth, smooth ? MicrofacetDistribution() : rough->distribution());
}

const Bsdf* PlasticMaterial::bsdf(const SurfaceInteraction& si, Arena& arena) const {
  if (rough_tex_) {
    float key;
    const MicrofacetDistribution d = rough_tex_->at(texture_query(si), &key);
    return arena.make<PlasticBsdf>(d, false, ior_, k_, &tex_tables_.at(key));
  }
  return arena.make<PlasticBsdf>(d_, smooth_, ior_, k_, &tables_);
}

}  // namespace kozu
