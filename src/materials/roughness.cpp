#include "materials/roughness.h"

#include "core/json_reader.h"

namespace kozu {

std::optional<RoughnessSpec> read_roughness(const JsonObject& desc) {
  RoughnessSpec spec;
  spec.type = microfacet_type_from_string(desc.get_enum("distribution", {"ggx", "beckmann"}, "ggx"));
  if (desc.has("gloss_model") && !desc.has("gloss")) desc.fail("gloss_model", "applies only with 'gloss'");
  const GlossModel model =
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
  if (present.empty()) return std::nullopt;

  if (desc.has("roughness")) {
    const float r = desc.get_float("roughness", {}, Range::unit());
    spec.alpha_x = spec.alpha_y = r * r;
  } else if (desc.has("alpha")) {
    spec.alpha_x = spec.alpha_y = desc.get_float("alpha", {}, Range::unit());
  } else if (aniso) {
    if (!desc.has("alpha_u") || !desc.has("alpha_v"))
      desc.fail(desc.has("alpha_u") ? "alpha_u" : "alpha_v", "give both 'alpha_u' and 'alpha_v'");
    spec.alpha_x = desc.get_float("alpha_u", {}, Range::unit());
    spec.alpha_y = desc.get_float("alpha_v", {}, Range::unit());
  } else {
    const float g = desc.get_float("gloss", {}, Range::unit());
    spec.alpha_x = spec.alpha_y = gloss_to_alpha(g, model);
    // RoughnessSpec::gloss is always the WWII gloss: convert an Advanced Warfare gloss through α.
    spec.gloss = model == GlossModel::WWII ? g : alpha_to_gloss(spec.alpha_x);
    return spec;
  }
  spec.gloss = alpha_to_gloss(std::sqrt(spec.alpha_x * spec.alpha_y));
  return spec;
}

}  // namespace kozu
