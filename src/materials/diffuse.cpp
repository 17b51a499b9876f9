#include "materials/diffuse.h"

#include "core/json_reader.h"
#include "core/warp.h"
#include "materials/cod_multiscatter_diffuse.h"
#include "materials/roughness.h"
#include "materials/shirley_diffuse.h"
#include "textures/texture_parse.h"

#include <fmt/format.h>

#include <algorithm>

#include <optional>

namespace kozu {

BsdfSample sample_cosine_lobe(const Vec3& wo, const Vec2& u) {
  BsdfSample s;
  if (wo.z == 0.0f) return s;
  Vec3 wi = warp::square_to_cosine_hemisphere(u);
  if (wi.z <= 0.0f) return s;     // grazing sample on the disk's rim
  if (wo.z < 0.0f) wi.z = -wi.z;  // two-sided: reflect on wo's side
  s.wi = wi;
  s.pdf = abs_cos_theta(wi) * kInvPi;
  s.flags = kBsdfReflection | kBsdfDiffuse;
  return s;
}

Rgb DiffuseBsdf::eval(const Vec3& wo, const Vec3& wi, TransportMode) const {
  if (!same_hemisphere(wo, wi)) return Rgb(0.0f);
  return albedo_ * (kInvPi * abs_cos_theta(wi));
}

BsdfSample DiffuseBsdf::sample(const Vec3& wo, float, const Vec2& u, TransportMode) const {
  BsdfSample s = sample_cosine_lobe(wo, u);
  if (s.valid()) s.f = albedo_ * s.pdf;
  return s;
}

float DiffuseBsdf::pdf(const Vec3& wo, const Vec3& wi) const { return cosine_lobe_pdf(wo, wi); }

int DiffuseBsdf::ltc_lobes(const Vec3& wo, const Vec3&, LtcLobe* out) const {
  if (!(wo.z > 0.0f)) return 0;  // seen from below, the lobe is the mirrored one; not worth a case
  out[0] = LtcLobe{Ltc(), albedo_};
  return 1;
}

int diffuse_ltc_lobe(const Bsdf& bsdf, const Vec3& wo, const Vec3& toward, LtcLobe* out) {
  if (!(wo.z > 0.0f)) return 0;
  const Vec3 w = toward.z > 1e-4f ? toward : Vec3(0.0f, 0.0f, 1.0f);
  out[0] = LtcLobe{Ltc(), bsdf.eval(wo, w, TransportMode::Radiance) * (kPi / w.z)};
  return 1;
}

Rgb DiffuseBsdf::eval_pdf(const Vec3& wo, const Vec3& wi, float* pdf_out, TransportMode) const {
  const float p = cosine_lobe_pdf(wo, wi);
  *pdf_out = p;
  return albedo_ * p;
}

namespace {

struct ModelName {
  DiffuseModel model;
  const char* name;
};
constexpr ModelName kModels[] = {
    {DiffuseModel::Lambert, "lambert"},
    {DiffuseModel::CodMultiscatter, "cod-multiscatter"},
    {DiffuseModel::Shirley, "shirley"},
};

const char* model_name(DiffuseModel model) {
  for (const auto& m : kModels)
    if (m.model == model) return m.name;
  return "?";
}

// Keys that only one model reads. Given to another model they fail with a message naming the model
// that reads them, which says more than finish()'s "unknown key".
struct ModelKey {
  const char* key;
  DiffuseModel model;
};
constexpr ModelKey kModelKeys[] = {
    {"gloss", DiffuseModel::CodMultiscatter},
    {"roughness", DiffuseModel::CodMultiscatter},
    {"alpha", DiffuseModel::CodMultiscatter},
    {"alpha_u", DiffuseModel::CodMultiscatter},
    {"alpha_v", DiffuseModel::CodMultiscatter},
    {"gloss_model", DiffuseModel::CodMultiscatter},
    {"f0", DiffuseModel::Shirley},
};

}  // namespace

Deferred<Material> DiffuseMaterial::parse(const JsonObject& desc, const MaterialParseContext& ctx) {
  std::vector<std::string> names;
  for (const auto& m : kModels) names.emplace_back(m.name);
  const std::string name = desc.get_enum("model", names, "lambert");
  DiffuseParams p;
  for (const auto& m : kModels)
    if (name == m.name) p.model = m.model;

  for (const auto& k : kModelKeys)
    if (k.model != p.model && desc.has(k.key))
      desc.fail(k.key, fmt::format("'{}' is read only by model '{}' (this material's model is '{}')", k.key,
                                   model_name(k.model), name));
  // read_roughness accepts `distribution`, but the CoD diffuse reads only the gloss.
  if (desc.has("distribution")) desc.fail("distribution", "no diffuse model has a microfacet distribution");

  std::optional<RoughnessTextureDesc> gloss;
  std::optional<Deferred<Texture>> albedo, f0;
  if (desc.has("albedo") && desc.raw("albedo").is_object())
    albedo = parse_texture(desc, "albedo", {TextureUse::Color, ctx.textures, Range::unit()});
  else
    p.albedo = desc.get_rgb("albedo", Rgb(0.5f), Range::unit());
  switch (p.model) {
    case DiffuseModel::Lambert:
      break;
    case DiffuseModel::CodMultiscatter:
      gloss = read_roughness_textures(desc, ctx.textures);
      if (!gloss)
        if (const auto spec = read_roughness(desc)) p.gloss = spec->gloss;
      break;
    case DiffuseModel::Shirley:
      if (desc.has("f0") && desc.raw("f0").is_object())
        f0 = parse_texture(desc, "f0", {TextureUse::Data, ctx.textures, Range::unit()});
      else
        p.f0 = desc.get_float("f0", 0.04f, Range::unit());
      break;
  }
  if (!albedo && !gloss && !f0) return std::make_unique<DiffuseMaterial>(p);
  auto texture = albedo ? std::make_shared<Deferred<Texture>>(std::move(*albedo)) : nullptr;
  auto f0_texture = f0 ? std::make_shared<Deferred<Texture>>(std::move(*f0)) : nullptr;
  return Deferred<Material>([p, texture, gloss, f0_texture]() -> std::unique_ptr<Material> {
    return std::make_unique<DiffuseMaterial>(p, texture ? texture->take() : nullptr, gloss ? gloss->build() : nullptr,
                                             f0_texture ? f0_texture->take() : nullptr);
  });
}

const Bsdf* DiffuseMaterial::bsdf(const SurfaceInteraction& si, Arena& arena) const {
  Rgb albedo = params_.albedo;
  if (albedo_texture_) albedo = glm::clamp(albedo_texture_->eval(texture_query(si)), Rgb(0.0f), Rgb(1.0f));
  switch (params_.model) {
    case DiffuseModel::CodMultiscatter:
      return arena.make<CodMultiscatterDiffuseBsdf>(
          albedo, gloss_texture_ ? gloss_texture_->gloss_at(texture_query(si)) : params_.gloss);
    case DiffuseModel::Shirley:
      return arena.make<ShirleyDiffuseBsdf>(
          albedo, f0_texture_ ? std::clamp(f0_texture_->eval_float(texture_query(si)), 0.0f, 1.0f) : params_.f0);
    case DiffuseModel::Lambert:
      break;
  }
  return arena.make<DiffuseBsdf>(albedo);
}

}  // namespace kozu
