#include "materials/roughness.h"

#include "core/json_reader.h"
#include "materials/roughness_tables.h"
#include "textures/texture_parse.h"

namespace kozu {

namespace {

const char* const kKeyNames[] = {"roughness", "alpha", "alpha_u", "gloss"};

struct Keys {
  MicrofacetType type;
  GlossModel model;
  std::optional<RoughnessKey> key;  // none of the keys given
};

// The checks every roughness description passes: one way of giving α, gloss_model only with gloss.
Keys read_keys(const JsonObject& desc) {
  Keys k;
  k.type = microfacet_type_from_string(desc.get_enum("distribution", {"ggx", "beckmann"}, "ggx"));
  if (desc.has("gloss_model") && !desc.has("gloss")) desc.fail("gloss_model", "applies only with 'gloss'");
  k.model =
      desc.get_enum("gloss_model", {"wwii", "aw"}, "wwii") == "aw" ? GlossModel::AdvancedWarfare : GlossModel::WWII;

  std::vector<const char*> present;
  for (const char* key : {"roughness", "alpha", "gloss"})
    if (desc.has(key)) present.push_back(key);
  const bool aniso = desc.has("alpha_u") || desc.has("alpha_v");
  if (aniso) present.push_back("alpha_u");
  if (present.size() > 1)
    desc.fail(present[1],
              std::string("give only one of 'roughness', 'alpha', 'alpha_u'/'alpha_v' or 'gloss' (also got '") +
                  present[0] + "')");
  if (present.empty()) return k;
  if (aniso && (!desc.has("alpha_u") || !desc.has("alpha_v")))
    desc.fail(desc.has("alpha_u") ? "alpha_u" : "alpha_v", "give both 'alpha_u' and 'alpha_v'");
  k.key = desc.has("roughness") ? RoughnessKey::Roughness
          : desc.has("alpha")   ? RoughnessKey::Alpha
          : aniso               ? RoughnessKey::Anisotropic
                                : RoughnessKey::Gloss;
  return k;
}

}  // namespace

MicrofacetDistribution roughness_distribution(MicrofacetType type, RoughnessKey key, GlossModel model, float x,
                                              float y) {
  switch (key) {
    case RoughnessKey::Roughness:
      return {type, x * x, x * x};
    case RoughnessKey::Alpha:
      return {type, x, x};
    case RoughnessKey::Anisotropic:
      return {type, x, y};
    case RoughnessKey::Gloss:
      break;
  }
  const float a = gloss_to_alpha(x, model);
  return {type, a, a};
}

std::optional<RoughnessSpec> read_roughness(const JsonObject& desc) {
  const Keys k = read_keys(desc);
  if (!k.key) return std::nullopt;
  RoughnessSpec spec;
  spec.type = k.type;
  if (*k.key == RoughnessKey::Roughness) {
    const float r = desc.get_float("roughness", {}, Range::unit());
    spec.alpha_x = spec.alpha_y = r * r;
  } else if (*k.key == RoughnessKey::Alpha) {
    spec.alpha_x = spec.alpha_y = desc.get_float("alpha", {}, Range::unit());
  } else if (*k.key == RoughnessKey::Anisotropic) {
    spec.alpha_x = desc.get_float("alpha_u", {}, Range::unit());
    spec.alpha_y = desc.get_float("alpha_v", {}, Range::unit());
  } else {
    const float g = desc.get_float("gloss", {}, Range::unit());
    spec.alpha_x = spec.alpha_y = gloss_to_alpha(g, k.model);
    // RoughnessSpec::gloss is always the WWII gloss: convert an Advanced Warfare gloss through α.
    spec.gloss = k.model == GlossModel::WWII ? g : alpha_to_gloss(spec.alpha_x);
    return spec;
  }
  spec.gloss = alpha_to_gloss(std::sqrt(spec.alpha_x * spec.alpha_y));
  return spec;
}

std::optional<RoughnessTextureDesc> read_roughness_textures(const JsonObject& desc,
                                                            const std::function<TextureCache*()>& textures) {
  bool textured = false;
  for (const char* key : {"roughness", "alpha", "alpha_u", "alpha_v", "gloss"})
    textured = textured || (desc.has(key) && desc.raw(key).is_object());
  if (!textured) return std::nullopt;
  const Keys k = read_keys(desc);
  RoughnessTextureDesc r;
  r.type = k.type;
  r.key = *k.key;
  r.model = k.model;
  const TextureParseContext ctx{TextureUse::Data, textures, Range::unit()};
  const char* first = r.key == RoughnessKey::Anisotropic ? "alpha_u" : kKeyNames[static_cast<int>(r.key)];
  r.u = std::make_shared<Deferred<Texture>>(parse_texture(desc, first, ctx));
  if (r.key == RoughnessKey::Anisotropic)
    r.v = std::make_shared<Deferred<Texture>>(parse_texture(desc, "alpha_v", ctx));
  return r;
}

std::unique_ptr<const TexturedRoughness> RoughnessTextureDesc::build() const {
  return std::make_unique<TexturedRoughness>(type, key, model, u->take(), v ? v->take() : nullptr);
}

TexturedRoughness::TexturedRoughness(MicrofacetType type, RoughnessKey key, GlossModel model,
                                     std::unique_ptr<const Texture> u, std::unique_ptr<const Texture> v)
    : type_(type), key_(key), model_(model), u_(std::move(u)), v_(std::move(v)) {
  constant_ = u_->is_constant() && (!v_ || v_->is_constant());
}

MicrofacetDistribution TexturedRoughness::at(const TextureQuery& q, float* table_key) const {
  // Only a varying texture is rounded (a plain alpha_v beside a textured alpha_u keeps its value).
  const auto value = [&](const Texture& t) {
    const float x = std::clamp(t.eval_float(q), 0.0f, 1.0f);
    return t.is_constant() ? x : RoughnessTables<int>::quantize(x);
  };
  const float x = value(*u_);
  const float y = v_ ? value(*v_) : x;
  const MicrofacetDistribution d = roughness_distribution(type_, key_, model_, x, y);
  *table_key = key_ == RoughnessKey::Anisotropic ? d.effective_alpha() : x;
  return d;
}

float TexturedRoughness::gloss_at(const TextureQuery& q) const {
  float key;
  const MicrofacetDistribution d = at(q, &key);
  // As read_roughness: a WWII gloss as given, any other key through eq. (2) inverted at the geometric-mean α.
  if (key_ == RoughnessKey::Gloss && model_ == GlossModel::WWII) return key;
  return alpha_to_gloss(std::sqrt(d.alpha_x() * d.alpha_y()));
}

std::optional<float> TexturedRoughness::constant_key() const {
  if (!constant_) return std::nullopt;
  float key;
  at(TextureQuery{}, &key);
  return key;
}

MicrofacetDistribution TexturedRoughness::table_distribution(float key) const {
  // alpha_u/alpha_v: the key is the RMS α itself; the others: the key is the texture's value.
  if (key_ == RoughnessKey::Anisotropic) return {type_, key, key};
  return roughness_distribution(type_, key_, model_, key, key);
}

}  // namespace kozu
