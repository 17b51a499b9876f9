#include "materials/standard.h"

#include "core/json_reader.h"
#include "core/warp.h"
#include "materials/cod_multiscatter_diffuse.h"
#include "materials/conductor.h"
#include "materials/diffuse.h"
#include "materials/fresnel.h"
#include "materials/ltc_table.h"
#include "materials/roughness.h"
#include "materials/sheen.h"
#include "textures/texture_parse.h"

#include <fmt/format.h>

namespace kozu {

namespace {

constexpr float kClearcoatIor = 1.5f;  // KHR_materials_clearcoat: the coat is a fixed IOR 1.5 layer

float mean(const Rgb& c) { return (c.r + c.g + c.b) / 3.0f; }

// A constant texture's value (its tables are built once, exactly), nullopt for a varying one.
std::optional<float> constant_value(const Texture& t) {
  if (!t.is_constant()) return std::nullopt;
  return t.eval(TextureQuery{}).r;
}

float alpha_of(float roughness) {
  return std::max(sqr(std::clamp(roughness, 0.0f, 1.0f)), MicrofacetDistribution::kMinAlpha);
}

// Schlick 1994: F0 + (1 − F0)(1 − cos)^5.
Rgb fresnel_schlick(const Rgb& f0, float cos_theta) {
  const float m = 1.0f - std::clamp(cos_theta, 0.0f, 1.0f);
  const float m2 = m * m;
  return f0 + (Rgb(1.0f) - f0) * (m2 * m2 * m);
}

// VNDF reflection density of h's reflection: D(h) G1(wo) / (4 μo) (Heitz & d'Eon 2014 eq. (2) over 4 (wo·h)).
float reflection_pdf(const MicrofacetDistribution& d, const Vec3& wo, const Vec3& h) {
  return d.D(h) / (4.0f * (1.0f + d.lambda(wo)) * wo.z);
}

// Single-scattering reflection D G2 / (4 μo) (times cos θi, without Fresnel), wo and wi on +z.
float reflection_value(const MicrofacetDistribution& d, const Vec3& wo, const Vec3& wi, const Vec3& h) {
  return d.D(h) / ((1.0f + d.lambda(wo) + d.lambda(wi)) * 4.0f * wo.z);
}

}  // namespace

// ---- tables ---------------------------------------------------------------------------------------------

StandardTables StandardTables::make(float alpha, float ior, bool glass) {
  StandardTables t;
  t.alpha = alpha;
  t.metal_e = AlbedoCurve([&](float mu) { return albedo::conductor_E(MicrofacetType::GGX, mu, alpha); });
  t.metal_lobe = CoupledLobe(t.metal_e);
  t.coat_e = AlbedoCurve([&](float mu) { return albedo::dielectric_ER(MicrofacetType::GGX, mu, alpha, ior); });
  t.coat_lobe = CoupledLobe(t.coat_e);
  if (glass) t.glass = DielectricCompensation::make(MicrofacetType::GGX, alpha, ior);
  t.gloss = alpha_to_gloss(alpha);
  return t;
}

ClearcoatTables ClearcoatTables::make(float alpha) {
  ClearcoatTables t;
  t.alpha = alpha;
  t.e = AlbedoCurve([&](float mu) { return albedo::dielectric_ER(MicrofacetType::GGX, mu, alpha, kClearcoatIor); });
  return t;
}

// ---- BSDF -----------------------------------------------------------------------------------------------

StandardBsdf::StandardBsdf(const StandardPoint& p, float ior, StandardDiffuse diffuse, const StandardTables* tables,
                           const ClearcoatTables* coat)
    : p_(p),
      ior_(ior),
      diffuse_(diffuse),
      tables_(tables),
      coat_(coat),
      d_(MicrofacetType::GGX, tables->alpha, tables->alpha),
      d_coat_(MicrofacetType::GGX, coat ? coat->alpha : 1.0f, coat ? coat->alpha : 1.0f),
      sheen_max_(std::max({p.sheen_color.r, p.sheen_color.g, p.sheen_color.b})),
      specular_mean_(mean(p.specular)),
      glass_(d_, ior, &tables->glass) {
  // ushiostarfish 2018: F_ms = F_avg² E_avg / (1 − F_avg (1 − E_avg)), with Schlick's F_avg = F0 + (1 − F0)/21.
  const Rgb f_avg = p_.base_color + (Rgb(1.0f) - p_.base_color) / 21.0f;
  const float e_avg = tables_->metal_e.average();
  f_ms_ = f_avg * f_avg * e_avg / (Rgb(1.0f) - f_avg * (1.0f - e_avg));
}

float StandardBsdf::narrowest_ltc_alpha() const {
  if (p_.transmission > 0.0f) return 1.0f;  // no lobes (ltc_lobes)
  return p_.clearcoat > 0.0f ? std::min(tables_->alpha, coat_->alpha) : tables_->alpha;
}

int StandardBsdf::ltc_lobes(const Vec3& wo, const Vec3& toward, LtcLobe* out) const {
  if (!(wo.z > 0.0f) || p_.transmission > 0.0f) return 0;
  const float mu = wo.z, alpha = tables_->alpha;
  int n = 0;
  if (p_.clearcoat > 0.0f)
    out[n++] = LtcLobe{ltc_lobe(LtcBrdf::GgxSpecular, wo, coat_->alpha).ltc, Rgb(p_.clearcoat * coat_->e.eval(mu))};
  const float layers = layer_transmittance(wo);
  Rgb cosine(0.0f);  // the clamped-cosine lobes (the metal's coupled lobe, the base) share one LTC
  if (p_.metallic > 0.0f) {
    const float m = p_.metallic * layers;
    const Rgb coupled = tables_->metal_lobe.active() ? f_ms_ * (1.0f - tables_->metal_e.eval(mu)) : Rgb(0.0f);
    Rgb metal_cosine(0.0f);
    out[n] = conductor_ltc_lobe(MicrofacetType::GGX, wo, alpha, p_.base_color, true, coupled, &metal_cosine);
    out[n++].weight *= m;
    cosine += m * metal_cosine;
  }
  const float opaque = (1.0f - p_.metallic) * layers;
  if (opaque > 0.0f) {
    const Rgb e_coat = p_.specular * tables_->coat_e.eval(mu);
    out[n++] = LtcLobe{ltc_lobe(LtcBrdf::GgxSpecular, wo, alpha).ltc, opaque * e_coat};
    LtcLobe base;
    if (diffuse_ == StandardDiffuse::Lambert)
      cosine += opaque * p_.base_color * (Rgb(1.0f) - e_coat);
    else if (diffuse_ltc_lobe(CodMultiscatterDiffuseBsdf(p_.base_color, tables_->gloss), wo, toward, &base))
      cosine += opaque * base.weight *
                (diffuse_ == StandardDiffuse::CodMultiscatterSplit
                     ? (Rgb(1.0f) - e_coat) * (Rgb(1.0f) - p_.specular * tables_->coat_e.eval(std::abs(toward.z)))
                     : Rgb(1.0f));
  }
  if (!is_black(cosine)) out[n++] = LtcLobe{Ltc(), cosine};
  return n;
}

uint32_t StandardBsdf::flags() const {
  uint32_t f = kBsdfReflection | kBsdfGlossy | kBsdfDiffuse;
  if (p_.transmission > 0.0f && p_.metallic < 1.0f) f |= kBsdfTransmission;
  return f;
}

float StandardBsdf::layer_transmittance(const Vec3& w) const {
  if (w.z <= 0.0f) return 1.0f;
  float t = 1.0f;
  if (p_.clearcoat > 0.0f) t *= 1.0f - p_.clearcoat * coat_->e.eval(w.z);
  if (sheen_max_ > 0.0f) t *= 1.0f - sheen_max_ * sheen::albedo(w.z, p_.sheen_roughness);
  return t;
}

std::array<float, StandardBsdf::kLobes> StandardBsdf::lobe_weights(const Vec3& wo) const {
  std::array<float, kLobes> w{};
  const float mu = std::abs(wo.z);
  float rest = 1.0f;
  if (wo.z > 0.0f) {
    if (p_.clearcoat > 0.0f) {
      w[kCoat] = p_.clearcoat * coat_->e.eval(mu);
      rest -= w[kCoat];
    }
    if (sheen_max_ > 0.0f) {
      w[kSheen] = rest * sheen_max_ * sheen::albedo(mu, p_.sheen_roughness);
      rest -= w[kSheen];
    }
  }
  const float metal = rest * p_.metallic, dielectric = rest * (1.0f - p_.metallic);
  const float e_metal = tables_->metal_e.eval(mu);
  w[kMetal] = metal * e_metal;
  if (tables_->metal_lobe.active()) w[kMetalMs] = metal * (1.0f - e_metal) * mean(f_ms_);
  const float opaque = dielectric * (1.0f - p_.transmission);
  const float e_coat = specular_mean_ * tables_->coat_e.eval(mu);
  w[kSpecular] = opaque * e_coat;
  w[kBase] = opaque * mean(p_.base_color) * (1.0f - e_coat);
  w[kGlass] = dielectric * p_.transmission;
  float sum = 0.0f;
  for (const float x : w) sum += x;
  if (sum > 0.0f)
    for (float& x : w) x /= sum;
  return w;
}

// Density of the base lobe: (1 − s̄ E_R(μ)) μ / (π (1 − s̄ E_R,avg)), the mixture of the cosine lobe (weight 1 − s̄)
// and the coupled lobe (1 − E_R(μ)) μ / (π (1 − E_R,avg)) (weight s̄ (1 − E_R,avg)), over their sum.
Rgb StandardBsdf::eval_opaque(const Vec3& wo, const Vec3& wi, const std::array<float, kLobes>& w, float* pdf) const {
  Rgb f(0.0f);
  const float mu_o = wo.z, mu_i = wi.z;
  const Vec3 h = glm::normalize(wo + wi);
  const float spec = reflection_value(d_, wo, wi, h);
  const float spec_pdf = reflection_pdf(d_, wo, h);
  const float cos_oh = glm::dot(wo, h);
  if (p_.metallic > 0.0f) {
    f += p_.metallic * fresnel_schlick(p_.base_color, cos_oh) * spec;
    *pdf += w[kMetal] * spec_pdf;
    if (tables_->metal_lobe.active()) {
      // ushiostarfish 2018 f_ms with k = F_ms: (1 − E(μo)) shape(μi) μi
      f += p_.metallic * f_ms_ * ((1.0f - tables_->metal_e.eval(mu_o)) * tables_->metal_lobe.shape(mu_i) * mu_i);
      *pdf += w[kMetalMs] * tables_->metal_lobe.pdf(mu_i);
    }
  }
  const float opaque = (1.0f - p_.metallic) * (1.0f - p_.transmission);
  if (opaque > 0.0f) {
    f += opaque * p_.specular * (fresnel_dielectric(cos_oh, ior_) * spec);
    *pdf += w[kSpecular] * spec_pdf;
    const AlbedoCurve& e = tables_->coat_e;
    if (diffuse_ == StandardDiffuse::Lambert) {
      // c (1 − s E_R(μo))(1 − s E_R(μi)) μi / (π (1 − s E_R,avg)), per channel of s
      const Rgb one(1.0f);
      const Rgb base = p_.base_color * (one - p_.specular * e.eval(mu_o)) * (one - p_.specular * e.eval(mu_i)) /
                       (one - p_.specular * e.average());
      f += opaque * base * (mu_i * kInvPi);
    } else {
      Rgb cod = CodMultiscatterDiffuseBsdf(p_.base_color, tables_->gloss).eval(wo, wi, TransportMode::Radiance);
      if (diffuse_ == StandardDiffuse::CodMultiscatterSplit)  // Chan 2018 §5.3: what the specular leaves, both ways
        cod *= (Rgb(1.0f) - p_.specular * e.eval(mu_o)) * (Rgb(1.0f) - p_.specular * e.eval(mu_i));
      f += opaque * cod;
    }
    *pdf += w[kBase] * (diffuse_ == StandardDiffuse::Lambert ? (1.0f - specular_mean_ * e.eval(mu_i)) * mu_i * kInvPi /
                                                                   (1.0f - specular_mean_ * e.average())
                                                             : mu_i * kInvPi);
  }
  return f;
}

Rgb StandardBsdf::eval_pdf(const Vec3& wo_in, const Vec3& wi_in, float* pdf_out, TransportMode mode) const {
  *pdf_out = 0.0f;
  const float s = flip(wo_in) ? -1.0f : 1.0f;
  const Vec3 wo(wo_in.x, wo_in.y, wo_in.z * s), wi(wi_in.x, wi_in.y, wi_in.z * s);
  if (wo.z == 0.0f || wi.z == 0.0f) return Rgb(0.0f);
  const std::array<float, kLobes> w = lobe_weights(wo);
  Rgb f(0.0f);
  float pdf = 0.0f;
  const bool outside = wo.z > 0.0f && wi.z > 0.0f;
  if (outside && p_.clearcoat > 0.0f) {
    const Vec3 h = glm::normalize(wo + wi);
    f += Rgb(p_.clearcoat * fresnel_dielectric(glm::dot(wo, h), kClearcoatIor) * reflection_value(d_coat_, wo, wi, h));
    pdf += w[kCoat] * reflection_pdf(d_coat_, wo, h);
  }
  const float coat_o = p_.clearcoat > 0.0f && wo.z > 0.0f ? 1.0f - p_.clearcoat * coat_->e.eval(wo.z) : 1.0f;
  const float coat_i = p_.clearcoat > 0.0f && wi.z > 0.0f ? 1.0f - p_.clearcoat * coat_->e.eval(wi.z) : 1.0f;
  if (outside && sheen_max_ > 0.0f) {
    f += coat_o * coat_i * p_.sheen_color * sheen::eval(wo, wi, p_.sheen_roughness);
    pdf += w[kSheen] * wi.z * kInvPi;
  }
  const float layers = layer_transmittance(wo) * layer_transmittance(wi);
  if (wo.z * wi.z > 0.0f) {
    // The opaque lobes are two-sided: evaluate them with wo on +z.
    const float z = wo.z > 0.0f ? 1.0f : -1.0f;
    const Vec3 o(wo.x, wo.y, wo.z * z), i(wi.x, wi.y, wi.z * z);
    float p = 0.0f;
    f += layers * eval_opaque(o, i, w, &p);
    pdf += p;
  }
  const float glass = (1.0f - p_.metallic) * p_.transmission;
  if (glass > 0.0f) {
    float p = 0.0f;
    Rgb g = glass_.eval_pdf(wo, wi, &p, mode);
    if (wo.z * wi.z < 0.0f) g *= p_.base_color;  // glTF: the transmitted light is tinted by the base colour
    f += layers * glass * g;
    pdf += w[kGlass] * p;
  }
  *pdf_out = pdf;
  return f;
}

BsdfSample StandardBsdf::sample(const Vec3& wo_in, float u_lobe, const Vec2& u, TransportMode mode) const {
  if (wo_in.z == 0.0f) return {};
  const float s = flip(wo_in) ? -1.0f : 1.0f;
  const Vec3 wo(wo_in.x, wo_in.y, wo_in.z * s);
  const std::array<float, kLobes> w = lobe_weights(wo);
  int lobe = 0;
  float cdf = 0.0f;
  for (; lobe < kLobes - 1; ++lobe) {
    if (u_lobe < cdf + w[lobe]) break;
    cdf += w[lobe];
  }
  if (!(w[lobe] > 0.0f)) return {};
  const float u_rest = std::min((u_lobe - cdf) / w[lobe], 0x1.fffffep-1f);  // reused within the lobe
  const float z = wo.z > 0.0f ? 1.0f : -1.0f;                               // the opaque lobes' side
  const Vec3 o(wo.x, wo.y, wo.z * z);
  Vec3 wi;
  uint32_t flags = kBsdfReflection | kBsdfGlossy;
  float eta = 1.0f;
  switch (lobe) {
    case kCoat:
      wi = reflect(wo, d_coat_.sample_visible(wo, u));
      break;
    case kSheen:
      wi = warp::square_to_cosine_hemisphere(u);
      flags = kBsdfReflection | kBsdfDiffuse;
      break;
    case kMetal:
    case kSpecular:
      wi = reflect(o, d_.sample_visible(o, u));
      wi.z *= z;
      break;
    case kMetalMs: {
      float p;
      wi = tables_->metal_lobe.sample(u, &p);
      wi.z *= z;
      flags = kBsdfReflection | kBsdfDiffuse;
      break;
    }
    case kBase: {
      // The base density's mixture (eval_opaque): the cosine lobe or the coupled one.
      const float e_avg = tables_->coat_e.average();
      const float p_cos =
          diffuse_ == StandardDiffuse::Lambert ? (1.0f - specular_mean_) / (1.0f - specular_mean_ * e_avg) : 1.0f;
      if (u_rest < p_cos || !tables_->coat_lobe.active()) {
        wi = warp::square_to_cosine_hemisphere(u);
      } else {
        float p;
        wi = tables_->coat_lobe.sample(u, &p);
      }
      wi.z *= z;
      flags = kBsdfReflection | kBsdfDiffuse;
      break;
    }
    case kGlass: {
      const BsdfSample g = glass_.sample(wo, u_rest, u, mode);
      if (!g.valid()) return {};
      wi = g.wi;
      flags = g.flags;
      eta = g.eta;
      break;
    }
  }
  if (wi.z == 0.0f) return {};
  if (lobe != kGlass && wi.z * wo.z < 0.0f) return {};  // reflected below the surface
  wi.z *= s;
  return sample_at(wo_in, wi, flags, mode, eta);
}

// ---- material -------------------------------------------------------------------------------------------

StandardMaterial::StandardMaterial(Textures textures, float ior, StandardDiffuse diffuse)
    : tex_(std::move(textures)),
      ior_(ior),
      diffuse_(diffuse),
      tables_(constant_value(*tex_.roughness),
              [ior, glass = !(tex_.transmission->is_constant() && tex_.transmission->eval({}).r == 0.0f)](float r) {
                return StandardTables::make(alpha_of(r), ior, glass);
              }),
      coat_tables_(constant_value(*tex_.clearcoat_roughness),
                   [](float r) { return ClearcoatTables::make(alpha_of(r)); }) {}

StandardPoint StandardMaterial::point(const TextureQuery& q) const {
  StandardPoint p;
  const auto unit = [](float x) { return std::clamp(x, 0.0f, 1.0f); };
  const auto unit_rgb = [](const Rgb& c) { return glm::clamp(c, Rgb(0.0f), Rgb(1.0f)); };
  p.base_color = unit_rgb(tex_.base_color->eval(q));
  p.metallic = unit(tex_.metallic->eval_float(q));
  p.alpha = unit(tex_.roughness->eval_float(q));  // the roughness; bsdf() maps it to its tables' α
  p.specular = unit_rgb(tex_.specular->eval_float(q) * tex_.specular_color->eval(q));
  p.transmission = unit(tex_.transmission->eval_float(q));
  p.clearcoat = unit(tex_.clearcoat->eval_float(q));
  p.clearcoat_alpha = unit(tex_.clearcoat_roughness->eval_float(q));
  p.sheen_color = unit_rgb(tex_.sheen_color->eval(q));
  p.sheen_roughness = unit(tex_.sheen_roughness->eval_float(q));
  return p;
}

const Bsdf* StandardMaterial::bsdf(const SurfaceInteraction& si, Arena& arena) const {
  StandardPoint p = point(texture_query(si));
  const StandardTables& t = tables_.at(p.alpha);
  p.alpha = t.alpha;
  const ClearcoatTables* coat = nullptr;
  if (p.clearcoat > 0.0f) {
    coat = &coat_tables_.at(p.clearcoat_alpha);
    p.clearcoat_alpha = coat->alpha;
  }
  return arena.make<StandardBsdf>(p, ior_, diffuse_, &t, coat);
}

Deferred<Material> StandardMaterial::parse(const JsonObject& desc, const MaterialParseContext& ctx) {
  struct Key {
    const char* name;
    std::unique_ptr<const Texture> Textures::*member;
    Rgb default_value;
    TextureUse use;
  };
  static const Key kKeys[] = {
      {"base_color", &Textures::base_color, Rgb(0.8f), TextureUse::Color},
      {"metallic", &Textures::metallic, Rgb(0.0f), TextureUse::Data},
      {"roughness", &Textures::roughness, Rgb(0.5f), TextureUse::Data},
      {"specular", &Textures::specular, Rgb(1.0f), TextureUse::Data},
      {"specular_color", &Textures::specular_color, Rgb(1.0f), TextureUse::Color},
      {"transmission", &Textures::transmission, Rgb(0.0f), TextureUse::Data},
      {"clearcoat", &Textures::clearcoat, Rgb(0.0f), TextureUse::Data},
      {"clearcoat_roughness", &Textures::clearcoat_roughness, Rgb(0.0f), TextureUse::Data},
      {"sheen_color", &Textures::sheen_color, Rgb(0.0f), TextureUse::Color},
      {"sheen_roughness", &Textures::sheen_roughness, Rgb(0.3f), TextureUse::Data},
  };
  const float ior = desc.get_float("ior", 1.5f, Range::closed(1.0, 3.0));
  const bool lambert = desc.get_enum("diffuse_model", {"lambert", "cod-multiscatter"}, "lambert") == "lambert";
  const bool split = desc.get_bool("cod_energy_split", false);
  if (split && lambert) desc.fail("cod_energy_split", "applies only to \"diffuse_model\": \"cod-multiscatter\"");
  const StandardDiffuse diffuse = lambert ? StandardDiffuse::Lambert
                                  : split ? StandardDiffuse::CodMultiscatterSplit
                                          : StandardDiffuse::CodMultiscatter;
  auto parsed = std::make_shared<std::vector<std::pair<const Key*, Deferred<Texture>>>>();
  for (const Key& k : kKeys)
    if (desc.has(k.name)) parsed->emplace_back(&k, parse_texture(desc, k.name, {k.use, ctx.textures, Range::unit()}));
  return Deferred<Material>([parsed, ior, diffuse]() -> std::unique_ptr<Material> {
    Textures t;
    for (const Key& k : kKeys) t.*k.member = std::make_unique<ConstantTexture>(k.default_value);
    for (auto& [key, texture] : *parsed) t.*key->member = texture.take();
    return std::make_unique<StandardMaterial>(std::move(t), ior, diffuse);
  });
}

}  // namespace kozu
