#include "textures/wwii_gloss_combine.h"

#include "core/json_reader.h"
#include "textures/detail_gloss.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace kozu {

namespace {
// Chan 2018 eq. (2) in float (materials/roughness.h has the same; textures sit below materials).
float gloss_to_alpha_wwii(float g) { return std::sqrt(2.0f / (1.0f + std::exp2(18.0f * g))); }
}  // namespace

Rgb WwiiGlossCombineTexture::eval(const TextureQuery& q) const {
  const float ga = std::clamp(base_->eval_float(q), 0.0f, 1.0f), gb = std::clamp(detail_->eval_float(q), 0.0f, 1.0f);
  const float g = method_ == Method::Exact ? DetailGlossTable::instance().combine(ga, gb)   // Chan 2018 eq. (34)
                                           : static_cast<float>(detail_gloss_fit(ga, gb));  // eq. (37)
  if (output_roughness_) return Rgb(std::sqrt(gloss_to_alpha_wwii(g)));  // r = sqrt(α), α by Chan 2018 eq. (2)
  return Rgb(g);
}

Deferred<Texture> parse_wwii_gloss_combine(const JsonObject& t, const TextureParseContext& ctx) {
  TextureParseContext inner = ctx;
  inner.use = TextureUse::Data;
  inner.range = Range::unit();
  for (const char* key : {"base", "detail"})
    if (!t.has(key)) t.fail(key, fmt::format("missing '{}' (the {} gloss texture)", key, key));
  auto base = std::make_shared<Deferred<Texture>>(parse_texture(t, "base", inner));
  auto detail = std::make_shared<Deferred<Texture>>(parse_texture(t, "detail", inner));
  const WwiiGlossCombineTexture::Method method = t.get_enum("method", {"exact", "fit"}, std::string("exact")) == "fit"
                                                     ? WwiiGlossCombineTexture::Method::Fit
                                                     : WwiiGlossCombineTexture::Method::Exact;
  const bool roughness = t.get_enum("output", {"gloss", "roughness"}, std::string("gloss")) == "roughness";
  if (method == WwiiGlossCombineTexture::Method::Exact) DetailGlossTable::instance();  // built once, while parsing
  return Deferred<Texture>([base, detail, method, roughness]() -> std::unique_ptr<Texture> {
    return std::make_unique<WwiiGlossCombineTexture>(base->take(), detail->take(), method, roughness);
  });
}

}  // namespace kozu
