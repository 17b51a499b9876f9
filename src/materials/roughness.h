// Roughness parameters shared by the microfacet materials: how a scene names α.
//
//   roughness      float  -  in [0, 1]  perceptual roughness r; α = r² (ushiostarfish 2018's convention)
//   alpha          float  -  in [0, 1]  α directly
//   alpha_u/alpha_v float -  in [0, 1]  anisotropic α along the shading frame's tangent / bitangent
//   gloss          float  -  in [0, 1]  Call of Duty gloss g, mapped by gloss_model:
//   gloss_model    string "wwii"        "wwii": α = sqrt(2 / (1 + 2^(18g)))  Chan 2018 eq. (2)
//                                       "aw":   α = sqrt(2 / (2 + 2^(16g)))  Chan 2018 eq. (1)
//   distribution   string "ggx"         "ggx" or "beckmann"
// At most one of roughness / alpha / alpha_u+alpha_v / gloss. Source: D. Chan, "Material Advances in Call of Duty:
// WWII", SIGGRAPH 2018 course Advances in Real-Time Rendering, §1.1.
//
// Textures: conductor, dielectric, plastic, subsurface and diffuse's cod-multiscatter also take each of roughness /
// alpha / alpha_u / alpha_v / gloss as a texture (textures/texture_parse.h; a number, TextureUse::Data, values clamped
// to [0, 1]). A textured roughness always makes a rough surface (the smooth/Dirac decision is taken when the scene is
// parsed); α below MicrofacetDistribution::kMinAlpha (1e-3) is clamped to it, as for any rough surface. A varying
// texture's values are rounded to 1/255 steps (an 8-bit texture's own) so that the compensation tables of each step are
// built once (roughness_tables.h): the keys' values are quantized, then mapped to α exactly as plain values are.
#pragma once

#include "core/registry.h"
#include "materials/microfacet.h"
#include "textures/texture.h"
#include "textures/texture_cache.h"

#include <functional>
#include <memory>
#include <optional>

namespace kozu {

class JsonObject;

enum class GlossModel { WWII, AdvancedWarfare };

// Chan 2018 eq. (2) (WWII) or eq. (1) (Advanced Warfare).
inline float gloss_to_alpha(float g, GlossModel model = GlossModel::WWII) {
  if (model == GlossModel::WWII) return std::sqrt(2.0f / (1.0f + std::exp2(18.0f * g)));
  return std::sqrt(2.0f / (2.0f + std::exp2(16.0f * g)));
}
// Inverse of eq. (2): the WWII gloss whose α is alpha (clamped to [0, 1]).
inline float alpha_to_gloss(float alpha) {
  alpha = std::clamp(alpha, 1e-6f, 1.0f);
  return std::clamp(std::log2(2.0f / (alpha * alpha) - 1.0f) / 18.0f, 0.0f, 1.0f);
}

struct RoughnessSpec {
  MicrofacetType type = MicrofacetType::GGX;
  float alpha_x = 0, alpha_y = 0;
  // The WWII gloss equivalent (given, or derived from α by inverting eq. (2)); the CoD diffuse uses it.
  float gloss = 1;
  // True when α is below MicrofacetDistribution::kMinAlpha on both axes: a smooth (delta) surface.
  bool smooth() const { return std::max(alpha_x, alpha_y) < MicrofacetDistribution::kMinAlpha; }
  MicrofacetDistribution distribution() const { return {type, alpha_x, alpha_y}; }
};

// Which key gives the roughness.
enum class RoughnessKey { Roughness, Alpha, Anisotropic, Gloss };

// The distribution the key's values x (and y: alpha_v, anisotropic only) give; the same arithmetic as
// read_roughness, so that a texture's value and the same plain value give the same bits.
MicrofacetDistribution roughness_distribution(MicrofacetType type, RoughnessKey key, GlossModel model, float x,
                                              float y);

// A roughness given by textures (any of the keys above as a texture; the other of alpha_u/alpha_v may be plain).
class TexturedRoughness {
 public:
  TexturedRoughness(MicrofacetType type, RoughnessKey key, GlossModel model, std::unique_ptr<const Texture> u,
                    std::unique_ptr<const Texture> v);
  // The distribution at q, and the key its tables are stored under (RoughnessTables::at): the texture's value for
  // the isotropic keys, the RMS α (MicrofacetDistribution::effective_alpha) for alpha_u/alpha_v. Varying textures'
  // values are quantized to 1/255 first (see the top of this file); constant ones are used as they are.
  MicrofacetDistribution at(const TextureQuery& q, float* table_key) const;
  // The table key of a constant roughness, nullopt for a varying one (RoughnessTables' constructor).
  std::optional<float> constant_key() const;
  // The distribution the tables of a table key are built for: a hit's own for the isotropic keys, the isotropic
  // one of the RMS α for alpha_u/alpha_v. table_alpha: its α.
  MicrofacetDistribution table_distribution(float key) const;
  float table_alpha(float key) const { return table_distribution(key).effective_alpha(); }
  MicrofacetType type() const { return type_; }
  // The WWII gloss at q (RoughnessSpec::gloss: the texture's value for a WWII `gloss`, else from α), for the CoD
  // diffuse.
  float gloss_at(const TextureQuery& q) const;

 private:
  MicrofacetType type_;
  RoughnessKey key_;
  GlossModel model_;
  std::unique_ptr<const Texture> u_, v_;  // v_: alpha_v, anisotropic only
  bool constant_;
};

// The roughness keys of a description in which at least one of them is a texture object, parsed; build() makes
// the TexturedRoughness once the textures are loaded (in the material's load job).
struct RoughnessTextureDesc {
  MicrofacetType type = MicrofacetType::GGX;
  RoughnessKey key = RoughnessKey::Roughness;
  GlossModel model = GlossModel::WWII;
  std::shared_ptr<Deferred<Texture>> u, v;
  std::unique_ptr<const TexturedRoughness> build() const;
};

// Reads the keys above when one of roughness / alpha / alpha_u / alpha_v / gloss is a texture object (a constant
// texture counts), with the same checks as read_roughness; nullopt otherwise (then call read_roughness).
std::optional<RoughnessTextureDesc> read_roughness_textures(const JsonObject& desc,
                                                            const std::function<TextureCache*()>& textures);

// Reads the keys above. Returns nullopt when none of roughness/alpha/alpha_u/alpha_v/gloss is given
// (the caller then uses its own default). `distribution` and `gloss_model` are read either way.
std::optional<RoughnessSpec> read_roughness(const JsonObject& desc);

}  // namespace kozu
