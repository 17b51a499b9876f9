#include "materials/subsurface.h"

#include "core/json_reader.h"
#include "core/rng.h"
#include "materials/diffuse.h"
#include "materials/fresnel.h"
#include "materials/roughness.h"
#include "textures/texture_parse.h"

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

namespace {
std::unique_ptr<const DielectricMaterial> boundary_of(float ior, bool smooth, const MicrofacetDistribution& d,
                                                      MultiscatterMode mode,
                                                      std::unique_ptr<const TexturedRoughness> rough) {
  if (rough) return std::make_unique<DielectricMaterial>(ior, std::move(rough), mode);
  return std::make_unique<DielectricMaterial>(ior, smooth, d, mode);
}
}  // namespace

SubsurfaceMaterial::SubsurfaceMaterial(const Rgb& albedo, const Rgb& length, SubsurfaceParameterization p, float ior,
                                       bool smooth, const MicrofacetDistribution& d, MultiscatterMode mode)
    : SubsurfaceMaterial(albedo, length, p, ior, smooth, d, mode, Textures{}) {}

SubsurfaceMaterial::SubsurfaceMaterial(const Rgb& albedo, const Rgb& length, SubsurfaceParameterization p, float ior,
                                       bool smooth, const MicrofacetDistribution& d, MultiscatterMode mode,
                                       Textures textures)
    : param_(p),
      albedo_tex_(std::move(textures.albedo)),
      length_tex_(std::move(textures.length)),
      albedo_(albedo),
      length_(length),
      boundary_(boundary_of(ior, smooth, d, mode, std::move(textures.roughness))),
      rough_textured_(boundary_->textured() && !boundary_->smooth()),
      tex_transmittance_(rough_textured_ ? boundary_->constant_table_key() : std::nullopt, [this](float key) {
        const RoughDielectricBsdf b = boundary_->level_bsdf(key);
        return AlbedoCurve([&](float mu) { return transmittance_by_sampling(b, mu); });
      }) {
  std::array<NormalizedDiffusion, 3> ch;
  for (int c = 0; c < 3; ++c) ch[c] = NormalizedDiffusion::from_length(p, albedo[c], length[c]);
  profile_ = RgbProfile(ch);
  if (boundary_->smooth()) {  // no roughness, or index-matched (dielectric.h)
    transmittance_ = AlbedoCurve([&](float mu) { return 1.0f - fresnel_dielectric(mu, ior); });
  } else if (!rough_textured_) {
    Arena arena;
    const Bsdf* b = boundary_->bsdf(SurfaceInteraction{}, arena);
    transmittance_ = AlbedoCurve([&](float mu) { return transmittance_by_sampling(*b, mu); });
  }
}

const AlbedoCurve& SubsurfaceMaterial::transmittance(const SurfaceInteraction& si) const {
  if (!rough_textured_) return transmittance_;
  return tex_transmittance_.at(boundary_->table_key_at(si));
}

const RgbProfile* SubsurfaceMaterial::subsurface_profile(const SurfaceInteraction& si, Arena& arena) const {
  if (!albedo_tex_ && !length_tex_) return &profile_;
  const TextureQuery q = texture_query(si);
  const Rgb albedo = albedo_tex_ ? glm::clamp(albedo_tex_->eval(q), Rgb(0.0f), Rgb(1.0f)) : albedo_;
  // A length must stay positive (d = ℓ / s divides).
  const Rgb length = length_tex_ ? glm::max(length_tex_->eval(q), Rgb(1e-6f)) : length_;
  std::array<NormalizedDiffusion, 3> ch;
  for (int c = 0; c < 3; ++c) ch[c] = NormalizedDiffusion::from_length(param_, albedo[c], length[c]);
  return arena.make<RgbProfile>(ch);
}

Deferred<Material> SubsurfaceMaterial::parse(const JsonObject& desc, const MaterialParseContext& ctx) {
  // A key given as a texture object is parsed as a texture; a plain value as before.
  const auto textured = [&](const char* key) { return desc.has(key) && desc.raw(key).is_object(); };
  std::shared_ptr<Deferred<Texture>> albedo_tex, length_tex;
  Rgb albedo(0.8f), length(1.0f);
  if (textured("albedo"))
    albedo_tex = std::make_shared<Deferred<Texture>>(
        parse_texture(desc, "albedo", {TextureUse::Color, ctx.textures, Range::unit()}));
  else
    albedo = desc.get_rgb("albedo", Rgb(0.8f), Range::unit());
  const bool has_mfp = desc.has("mfp"), has_dmfp = desc.has("dmfp");
  if (has_mfp == has_dmfp)
    desc.fail(has_mfp ? "dmfp" : "mfp", "give exactly one of \"mfp\" (volume mean free path) and \"dmfp\" "
                                        "(diffuse mean free path), per color channel, in scene units");
  const char* length_key = has_mfp ? "mfp" : "dmfp";
  if (textured(length_key))
    length_tex = std::make_shared<Deferred<Texture>>(
        parse_texture(desc, length_key, {TextureUse::Data, ctx.textures, Range::positive()}));
  else
    length = desc.get_rgb(length_key, {}, Range::positive());
  const std::string pz = desc.get_enum("parameterization", {"searchlight", "diffuse", "dmfp"},
                                       has_dmfp ? "dmfp" : "searchlight");
  if ((pz == "dmfp") != has_dmfp)
    desc.fail("parameterization", has_dmfp ? "\"" + pz + "\" is a parameterization of the mean free path: use \"mfp\""
                                           : "\"dmfp\" needs the \"dmfp\" key instead of \"mfp\"");
  const SubsurfaceParameterization p = pz == "dmfp"      ? SubsurfaceParameterization::Dmfp
                                       : pz == "diffuse" ? SubsurfaceParameterization::Diffuse
                                                         : SubsurfaceParameterization::Searchlight;
  const float ior = desc.get_float("ior", 1.4f, Range::positive());
  const std::optional<RoughnessTextureDesc> rough_textures = read_roughness_textures(desc, ctx.textures);
  std::optional<RoughnessSpec> rough;
  if (!rough_textures) rough = read_roughness(desc);
  const std::string ms = desc.get_enum("multiscatter", {"none", "compensated"}, "compensated");
  const MultiscatterMode mode = ms == "compensated" ? MultiscatterMode::Compensated : MultiscatterMode::None;
  const bool smooth = !rough_textures && (!rough || rough->smooth());
  const MicrofacetDistribution d = smooth || rough_textures ? MicrofacetDistribution() : rough->distribution();
  if (!albedo_tex && !length_tex && !rough_textures)
    return std::make_unique<SubsurfaceMaterial>(albedo, length, p, ior, smooth, d, mode);
  const auto rough_tex = rough_textures ? std::make_shared<RoughnessTextureDesc>(*rough_textures) : nullptr;
  return Deferred<Material>(
      [albedo, length, p, ior, smooth, d, mode, albedo_tex, length_tex, rough_tex]() -> std::unique_ptr<Material> {
        Textures t;
        if (albedo_tex) t.albedo = albedo_tex->take();
        if (length_tex) t.length = length_tex->take();
        if (rough_tex) t.roughness = rough_tex->build();
        return std::make_unique<SubsurfaceMaterial>(albedo, length, p, ior, smooth, d, mode, std::move(t));
      });
}

const Bsdf* SubsurfaceMaterial::bsdf(const SurfaceInteraction& si, Arena& arena) const {
  return arena.make<SubsurfaceBoundaryBsdf>(boundary_->bsdf(si, arena));
}

}  // namespace kozu
