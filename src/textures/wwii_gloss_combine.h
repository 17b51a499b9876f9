// wwii_gloss_combine: a WWII gloss texture that combines a base gloss texture with a detail gloss texture by Chan
// 2018 eq. (34) (or its fit, eq. (37)): textures/detail_gloss.h. The renderer puts it in as a material's "gloss" when
// a detail normal map is filtered (materials/normal_gloss_filtering.h); it can also be given by hand.
//
// Source: D. Chan, "Material Advances in Call of Duty: WWII", SIGGRAPH 2018 course Advances in Real-Time Rendering
// in Games, §2.4, eqs. (34)-(37).
//
// Parameters
//   base    texture  required  the base gloss (first channel; values clamped to [0, 1])
//   detail  texture  required  the detail gloss (first channel; values clamped to [0, 1])
//   method  string   "exact"   "exact": eq. (34) by DetailGlossTable; "fit": eq. (37) with eqs. (35)-(36)'s
//                              coefficients
//   output  string   "gloss"   "gloss": the combined WWII gloss g; "roughness": r = sqrt(α(g)) with α by eq. (2) (for
//                              the standard material's roughness, α = r²)
// Both textures are looked up at the same (u, v) and footprint (each applies its own uv_scale / uv_offset).
#pragma once

#include "core/registry.h"
#include "textures/texture.h"
#include "textures/texture_parse.h"

#include <memory>

namespace kozu {

class WwiiGlossCombineTexture final : public Texture {
 public:
  enum class Method { Exact, Fit };
  WwiiGlossCombineTexture(std::unique_ptr<const Texture> base, std::unique_ptr<const Texture> detail, Method method,
                          bool output_roughness = false)
      : base_(std::move(base)), detail_(std::move(detail)), method_(method), output_roughness_(output_roughness) {}
  Rgb eval(const TextureQuery& q) const override;
  bool is_constant() const override { return base_->is_constant() && detail_->is_constant(); }

 private:
  std::unique_ptr<const Texture> base_, detail_;
  Method method_;
  bool output_roughness_;
};

// The texture table's parser (textures/texture_parse.cpp).
Deferred<Texture> parse_wwii_gloss_combine(const JsonObject& t, const TextureParseContext& ctx);

}  // namespace kozu
