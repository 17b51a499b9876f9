#include "materials/normal_gloss_filtering.h"

#include "core/error.h"
#include "materials/microfacet.h"
#include "textures/normal_gloss_files.h"
#include "textures/normal_gloss_filter.h"

#include <fmt/format.h>

#include <cmath>
#include <functional>
#include <mutex>

namespace kozu {

namespace {

// Bumped when the filtering or its files change, so that old files are not reused.
constexpr int kFilteringVersion = 1;

bool is_string(const Json& j, const char* key, std::string* value) {
  if (!j.contains(key) || !j[key].is_string()) return false;
  *value = j[key].get<std::string>();
  return true;
}

// The two files of a map filtered from a gloss, in the texture cache's folder, named by a key that hashes the map's
// absolute path, size and modification time (as the cache's own conversions), the gloss, the model and the version.
// False when the map cannot be read (its image parser names the error).
bool filtered_file_names(const std::filesystem::path& map, double gloss, const std::filesystem::path& dir,
                         std::filesystem::path* out_normal, std::filesystem::path* out_gloss) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(map, ec);
  if (ec) return false;
  const auto mtime = std::filesystem::last_write_time(map, ec).time_since_epoch().count();
  const std::filesystem::path absolute = std::filesystem::absolute(map, ec);
  const size_t hash = std::hash<std::string>{}(fmt::format("{}|{}|{}|{:.17g}|macro|{}", absolute.string(), size,
                                                           static_cast<long long>(mtime), gloss, kFilteringVersion));
  const std::string stem = fmt::format("{}-{:016x}", map.stem().string(), hash);
  *out_normal = dir / (stem + ".normal.exr");
  *out_gloss = dir / (stem + ".gloss.exr");
  return true;
}

}  // namespace

std::optional<NormalGlossFilteringPlan> plan_normal_gloss_filtering(const JsonObject& desc,
                                                                    const MaterialParseContext& ctx) {
  const bool given = desc.has("normal_gloss_filtering");
  const bool on = desc.get_bool("normal_gloss_filtering", true);
  if (given && !desc.has("normal_map"))
    desc.fail("normal_gloss_filtering", "'normal_gloss_filtering' needs a 'normal_map'");
  if (!on || !desc.has("normal_map") || !ctx.textures) return std::nullopt;
  // Combinations this step does not filter keep their level-0 lookups; asked for by name, one warning says why.
  const auto skip = [&](const std::string& why) -> std::optional<NormalGlossFilteringPlan> {
    if (given) desc.warn("normal_gloss_filtering", "not applied: " + why);
    return std::nullopt;
  };

  const Json& map = desc.raw("normal_map");
  std::string s;
  if (!map.is_object() || !is_string(map, "type", &s) || s != "image")
    return skip("the normal map is not an \"image\" texture");
  if (!is_string(map, "file", &s) || s.empty()) return std::nullopt;  // its parser names the error
  if (map.contains("channel")) return skip("the normal map reads one channel");
  if (is_string(map, "colorspace", &s) && s == "srgb") return skip("the normal map is decoded as sRGB");
  // Level 0 is the authored map: nothing to filter.
  if (is_string(map, "filter", &s) && s == "closest") return std::nullopt;
  if (desc.has("normal_map_strength") &&
      !(desc.raw("normal_map_strength").is_number() && desc.raw("normal_map_strength").get<double>() == 1.0))
    return skip("normal_map_strength is not 1");

  if (!desc.has("type") || !desc.raw("type").is_string()) return std::nullopt;  // parse_by_type names the error
  s = desc.raw("type").get<std::string>();
  if (s != "conductor" && s != "dielectric" && s != "plastic" && s != "subsurface")
    return skip(fmt::format("a \"{}\" material's roughness is not filtered", s));
  if (desc.has("distribution") && !(desc.raw("distribution").is_string() && desc.raw("distribution") == "ggx"))
    return skip("the distribution is not \"ggx\"");
  if (desc.has("alpha_u") || desc.has("alpha_v")) return skip("the roughness is anisotropic");
  const char* key = nullptr;
  for (const char* k : {"roughness", "alpha", "gloss"})
    if (desc.has(k)) {
      if (key) return std::nullopt;  // the material's parser names the error
      key = k;
    }
  if (!key) return skip("no roughness is given");
  if (!desc.raw(key).is_number()) return skip(fmt::format("'{}' is not a plain number", key));
  const double x = desc.raw(key).get<double>();
  if (!(x >= 0.0 && x <= 1.0)) return std::nullopt;  // the material's parser names the error
  const bool aw = std::string_view(key) == "gloss" && desc.has("gloss_model") && desc.raw("gloss_model").is_string() &&
                  desc.raw("gloss_model") == "aw";
  // The material's α (materials/roughness.h: α = r², α, or the gloss through Chan 2018 eq. (2) or (1)).
  const double alpha = std::string_view(key) == "roughness" ? x * x
                       : std::string_view(key) == "alpha"   ? x
                       : aw                                 ? std::sqrt(2.0 / (2.0 + std::exp2(16.0 * x)))  // eq. (1)
                                                            : wwii_gloss_to_alpha(x);                                                       // eq. (2)
  if (alpha < MicrofacetDistribution::kMinAlpha) return skip("the surface is smooth");
  NormalGlossFilteringPlan plan;
  plan.gloss = std::string_view(key) == "gloss" && !aw ? x : wwii_alpha_to_gloss(alpha);  // Chan 2018 eq. (2)

  plan.normal_map = desc.get_object("normal_map").get_path("file");  // recorded as an input of the render
  const std::filesystem::path dir = ctx.textures()->convert_folder();
  if (!filtered_file_names(plan.normal_map, plan.gloss, dir, &plan.out_normal, &plan.out_gloss)) return std::nullopt;

  // A detail normal map is filtered too, from gloss 1 (its level 0 adds no roughness of its own): its gloss chain
  // says how much of its variation each of its levels lost, combined with the base's at each lookup by Chan 2018
  // eq. (34) or (37) (textures/wwii_gloss_combine.h). A detail map this step cannot filter keeps its own mip lookups.
  std::string detail_gloss = "exact";
  if (desc.has("detail_gloss") && desc.raw("detail_gloss").is_string())
    detail_gloss = desc.raw("detail_gloss").get<std::string>();
  if (detail_gloss != "exact" && detail_gloss != "fit") return std::nullopt;  // parse_surface_maps names the error
  const Json* detail = desc.has("detail_normal_map") ? &desc.raw("detail_normal_map") : nullptr;
  if (detail) {
    std::string why;
    if (!detail->is_object() || !is_string(*detail, "type", &s) || s != "image")
      why = "the detail normal map is not an \"image\" texture";
    else if (!is_string(*detail, "file", &s) || s.empty())
      return std::nullopt;  // its parser names the error
    else if (detail->contains("channel"))
      why = "the detail normal map reads one channel";
    else if (is_string(*detail, "colorspace", &s) && s == "srgb")
      why = "the detail normal map is decoded as sRGB";
    else if (is_string(*detail, "filter", &s) && s == "closest")
      why = "the detail normal map reads level 0 only";
    if (!why.empty()) {
      if (desc.has("detail_gloss")) desc.warn("detail_gloss", "not applied: " + why);
      detail = nullptr;
    } else {
      plan.detail_normal_map = desc.get_object("detail_normal_map").get_path("file");
      if (!filtered_file_names(plan.detail_normal_map, 1.0, dir, &plan.out_detail_normal, &plan.out_detail_gloss))
        return std::nullopt;
    }
  }

  // The description the material is parsed from: the filtered chains in place of the map and the roughness.
  plan.json = std::make_shared<Json>(Json::object());
  Json& j = *plan.json;
  for (const std::string& k : desc.keys())
    if (k != "normal_gloss_filtering" && k != "roughness" && k != "alpha" && k != "gloss" && k != "gloss_model")
      j[k] = desc.raw(k);
  j["normal_map"]["file"] = plan.out_normal.string();
  j["normal_map"]["colorspace"] = "linear";
  const auto gloss_chain = [](const Json& map, const std::filesystem::path& file) {
    Json gloss = {{"type", "image"}, {"file", file.string()}, {"colorspace", "linear"}};
    for (const char* k : {"uv_scale", "uv_offset", "uv_rotation", "filter"})
      if (map.contains(k)) gloss[k] = map[k];
    return gloss;
  };
  // A WWII gloss: α = eq. (2) of the filtered value at each lookup.
  j["gloss"] = gloss_chain(map, plan.out_gloss);
  if (detail) {
    j["detail_normal_map"]["file"] = plan.out_detail_normal.string();
    j["detail_normal_map"]["colorspace"] = "linear";
    j["gloss"] = {{"type", "wwii_gloss_combine"},
                  {"base", j["gloss"]},
                  {"detail", gloss_chain(*detail, plan.out_detail_gloss)},
                  {"method", detail_gloss}};
  }
  return plan;
}

void NormalGlossFilteringPlan::build() const {
  // One build at a time: the files' temporary names are unique per process, not per thread, and two materials may
  // share a map and a gloss (the second then finds the files).
  static std::mutex mutex;
  std::lock_guard lock(mutex);
  const auto build_one = [](const std::filesystem::path& in, double gloss, const std::filesystem::path& normal,
                            const std::filesystem::path& gloss_file) {
    std::error_code ec;
    if (std::filesystem::file_size(normal, ec) > 0 && !ec && std::filesystem::file_size(gloss_file, ec) > 0 && !ec)
      return;
    std::filesystem::create_directories(normal.parent_path(), ec);
    NormalGlossFilterJob job;
    job.normal_map = in;
    job.gloss_value = gloss;
    job.out_normal = normal;
    job.out_gloss = gloss_file;
    job.model = ShortenedNormalModel::Macro;  // Chan 2018 Algorithm 2, as shipped
    filter_normal_gloss_files(job);
  };
  build_one(normal_map, gloss, out_normal, out_gloss);
  if (!detail_normal_map.empty()) build_one(detail_normal_map, 1.0, out_detail_normal, out_detail_gloss);
}

}  // namespace kozu
