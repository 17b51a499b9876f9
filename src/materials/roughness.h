// Roughness parameters shared by the microfacet materials: how a scene names α.
//
//   roughness      float  -  in [0, 1]  perceptual roughness r; α = r² (the seed 002 convention)
//   alpha          float  -  in [0, 1]  α directly
//   alpha_u/alpha_v float -  in [0, 1]  anisotropic α along the shading frame's tangent / bitangent
//   gloss          float  -  in [0, 1]  Call of Duty gloss g, mapped by gloss_model:
//   gloss_model    string "wwii"        "wwii": α = sqrt(2 / (1 + 2^(18g)))  seed 004 eq. (2)
//                                       "aw":   α = sqrt(2 / (2 + 2^(16g)))  seed 004 eq. (1)
//   distribution   string "ggx"         "ggx" or "beckmann"
// At most one of roughness / alpha / alpha_u+alpha_v / gloss. Seed: ../shared/seeds/004_36902cd47dec0c2e.txt §1.1.
#pragma once

#include "materials/microfacet.h"

#include <optional>

namespace kozu {

class JsonObject;

enum class GlossModel { WWII, AdvancedWarfare };

// seed 004 eq. (2) (WWII) or eq. (1) (Advanced Warfare).
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

// Reads the keys above. Returns nullopt when none of roughness/alpha/alpha_u/alpha_v/gloss is given
// (the caller then uses its own default). `distribution` and `gloss_model` are read either way.
std::optional<RoughnessSpec> read_roughness(const JsonObject& desc);

}  // namespace kozu
