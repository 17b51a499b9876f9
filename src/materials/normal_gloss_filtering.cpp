#include "materials/normal_gloss_filtering.h"

#include "core/error.h"
#include "io/image_io.h"
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

// A material's roughness value x as GGX α (materials/roughness.h): α = r², α, or the gloss through Chan 2018 eq. (2)
// (WWII) or eq. (1) (Advanced Warfare).
double roughness_to_alpha(RoughnessKind kind, double x) {
  x = std::clamp(x, 0.0, 1.0);
  switch (kind) {
    case RoughnessKind::Roughness:
      return x * x;
    case RoughnessKind::Alpha:
      return x;
    case RoughnessKind::GlossAw:
      return std::sqrt(2.0 / (2.0 + std::exp2(16.0 * x)));  // eq. (1)
    case RoughnessKind::Gloss:
      break;
  }
  return wwii_gloss_to_alpha(x);  // eq. (2)
}

// "<stem>.gloss.exr" -> "<stem><suffix>".
std::filesystem::path replace_suffix(const std::filesystem::path& gloss_file, const std::string& suffix) {
  std::string name = gloss_file.filename().string();
  name.resize(name.size() - std::string_view(".gloss.exr").size());
  return gloss_file.parent_path() / (name + suffix);
}

// The two files of a map filtered from a gloss, in the texture cache's folder, named by a key that hashes the map's
// absolute path, size and modification time (as the cache's own conversions), the gloss, the model and the version.
// False when the map cannot be read (its image parser names the error).
bool filtered_file_names(const std::filesystem::path& map, double gloss, const std::string& roughness_key,
                         const std::filesystem::path& dir, std::filesystem::path* out_normal,
                         std::filesystem::path* out_gloss) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(map, ec);
  if (ec) return false;
  const auto mtime = std::filesystem::last_write_time(map, ec).time_since_epoch().count();
  const std::filesystem::path absolute = std::filesystem::absolute(map, ec);
  std::string what = fmt::format("{}|{}|{}|{:.17g}|macro|{}", absolute.string(), size, static_cast<long long>(mtime),
                                 gloss, kFilteringVersion);
  if (!roughness_key.empty()) what += "|" + roughness_key;  // a textured roughness, or a standard material's
  const size_t hash = std::hash<std::string>{}(what);
  const std::string stem = fmt::format("{}-{:016x}", map.stem().string(), hash);
  *out_normal = dir / (stem + ".normal.exr");
  *out_gloss = dir / (stem + ".gloss.exr");
  return true;
}

// Why a material is not filtered: Skip (a combination this step does not filter: one warning when the key was given),
// Quiet (an error the material's own parser names, or nothing to filter); Go when it is.
struct Verdict {
  enum Kind { Go, Skip, Quiet } kind = Go;
  std::string why;
  static Verdict skip(std::string w) { return {Skip, std::move(w)}; }
  static Verdict quiet() { return {Quiet, {}}; }
};

// The normal map: an image the renderer reads as three channels of data, not at level 0 only. *strength: its
// normal_map_strength (applied to the texels before filtering, materials/normal_map.h; the chain is read at 1).
Verdict check_normal_map(const JsonObject& desc, double* strength) {
  const Json& map = desc.raw("normal_map");
  std::string s;
  if (!map.is_object() || !json_string(map, "type", &s) || s != "image")
    return Verdict::skip("the normal map is not an \"image\" texture");
  if (!json_string(map, "file", &s) || s.empty()) return Verdict::quiet();  // its parser names the error
  if (map.contains("channel")) return Verdict::skip("the normal map reads one channel");
  if (json_string(map, "colorspace", &s) && s == "srgb") return Verdict::skip("the normal map is decoded as sRGB");
  // Level 0 is the authored map: nothing to filter.
  if (json_string(map, "filter", &s) && s == "closest") return Verdict::quiet();
  *strength = 1.0;
  if (desc.has("normal_map_strength")) {
    const Json& v = desc.raw("normal_map_strength");
    if (!v.is_number() || !(v.get<double>() >= 0.0) || !std::isfinite(v.get<double>()))
      return Verdict::quiet();  // parse_surface_maps names the error
    *strength = v.get<double>();
  }
  return {};
}

// A textured roughness under `key`: an image of the normal map's (u, v) mapping, converted to gloss per texel at
// build time. Fills the plan's roughness image, channel and scale; *file_key: what of it the file names hash.
Verdict plan_roughness_image(const JsonObject& desc, const char* key, NormalGlossFilteringPlan* plan,
                             std::string* file_key) {
  const Json& map = desc.raw("normal_map");
  const Json& r = desc.raw(key);
  std::string s;
  if (!json_string(r, "type", &s) || s != "image")
    return Verdict::skip(fmt::format("'{}' is not an \"image\" texture", key));
  if (!json_string(r, "file", &s) || s.empty()) return Verdict::quiet();  // its parser names the error
  if (json_string(r, "colorspace", &s) && s == "srgb")
    return Verdict::skip(fmt::format("'{}' is decoded as sRGB", key));
  for (const char* k : {"uv_scale", "uv_offset", "uv_rotation"})
    if (r.contains(k) != map.contains(k) || (r.contains(k) && r[k] != map[k]))
      return Verdict::skip(fmt::format("'{}' and the normal map differ in {}", key, k));
  if (r.contains("threshold")) return Verdict::skip(fmt::format("'{}' has a threshold", key));
  if (r.contains("channel")) {
    if (!json_string(r, "channel", &s) || s.size() != 1 || std::string_view("rgba").find(s[0]) == std::string::npos)
      return Verdict::quiet();  // its parser names the error
    plan->roughness_channel = static_cast<int>(std::string_view("rgba").find(s[0]));
  }
  if (r.contains("scale")) {
    const Json& sc = r["scale"];
    if (sc.is_number())
      plan->roughness_scale = sc.get<double>();
    else if (sc.is_array() && sc.size() == 3 && sc[0].is_number() && sc[0] == sc[1] && sc[1] == sc[2])
      plan->roughness_scale = sc[0].get<double>();
    else
      return Verdict::skip(fmt::format("'{}' has a scale per channel", key));
  }
  plan->roughness_map = desc.get_object(key).get_path("file");
  plan->roughness_key_name = key;
  std::error_code ec;
  const auto size = std::filesystem::file_size(plan->roughness_map, ec);
  if (ec) return Verdict::quiet();  // the image parser names the missing file
  const auto mtime = std::filesystem::last_write_time(plan->roughness_map, ec).time_since_epoch().count();
  *file_key = fmt::format("{}|{}|{}|{}|{:.17g}", std::filesystem::absolute(plan->roughness_map, ec).string(), size,
                          static_cast<long long>(mtime), plan->roughness_channel, plan->roughness_scale);
  return {};
}

// The material's type and roughness: an isotropic GGX microfacet material whose roughness is one plain number or an
// image (standard: its "roughness", 0.5 when absent). Fills the plan's roughness; *file_key as above.
Verdict plan_roughness(const JsonObject& desc, NormalGlossFilteringPlan* plan, std::string* file_key) {
  if (!desc.has("type") || !desc.raw("type").is_string()) return Verdict::quiet();  // parse_by_type names the error
  const std::string type = desc.raw("type").get<std::string>();
  const bool standard = type == "standard";
  if (!standard && type != "conductor" && type != "dielectric" && type != "plastic" && type != "subsurface")
    return Verdict::skip(fmt::format("a \"{}\" material's roughness is not filtered", type));
  if (desc.has("distribution") && !(desc.raw("distribution").is_string() && desc.raw("distribution") == "ggx"))
    return Verdict::skip("the distribution is not \"ggx\"");
  if (desc.has("alpha_u") || desc.has("alpha_v")) return Verdict::skip("the roughness is anisotropic");
  const char* key = nullptr;
  for (const char* k : {"roughness", "alpha", "gloss"})
    if (desc.has(k)) {
      if (key) return Verdict::quiet();  // the material's parser names the error
      key = k;
    }
  // standard: "roughness" r only, 0.5 when absent (materials/standard.h).
  if (standard && key && std::string_view(key) != "roughness") return Verdict::quiet();  // its parser names the key
  if (!key && !standard) return Verdict::skip("no roughness is given");
  const bool aw = key && std::string_view(key) == "gloss" && desc.has("gloss_model") &&
                  desc.raw("gloss_model").is_string() && desc.raw("gloss_model") == "aw";
  plan->roughness_kind = !key                                   ? RoughnessKind::Roughness
                         : std::string_view(key) == "roughness" ? RoughnessKind::Roughness
                         : std::string_view(key) == "alpha"     ? RoughnessKind::Alpha
                         : aw                                   ? RoughnessKind::GlossAw
                                                                : RoughnessKind::Gloss;
  plan->standard = standard;
  if (key && desc.raw(key).is_object()) {
    const Verdict v = plan_roughness_image(desc, key, plan, file_key);
    if (v.kind != Verdict::Go) return v;
  } else {
    if (key && !desc.raw(key).is_number()) return Verdict::skip(fmt::format("'{}' is not a number or an image", key));
    const double x = key ? desc.raw(key).get<double>() : 0.5;
    if (!(x >= 0.0 && x <= 1.0)) return Verdict::quiet();  // the material's parser names the error
    // The material's α (materials/roughness.h: α = r², α, or the gloss through Chan 2018 eq. (2) or (1)).
    const double alpha = roughness_to_alpha(plan->roughness_kind, x);
    // A smooth conductor etc. stays a Dirac one; standard clamps α to kMinAlpha and is always rough.
    if (!standard && alpha < MicrofacetDistribution::kMinAlpha) return Verdict::skip("the surface is smooth");
    plan->gloss = plan->roughness_kind == RoughnessKind::Gloss ? x : wwii_alpha_to_gloss(alpha);  // Chan 2018 eq. (2)
  }
  *file_key += fmt::format("|{}|{}", static_cast<int>(plan->roughness_kind), standard);
  return {};
}

// A detail normal map is filtered too, from gloss 1 (its level 0 adds no roughness of its own): its gloss chain says
// how much of its variation each of its levels lost, combined with the base's at each lookup by Chan 2018 eq. (34)
// or (37) (textures/wwii_gloss_combine.h). A detail map this step cannot filter keeps its own mip lookups (one
// warning when detail_gloss was given). *detail: the detail map's description, or null when it is not filtered.
Verdict plan_detail(const JsonObject& desc, const std::filesystem::path& dir, NormalGlossFilteringPlan* plan,
                    const Json** detail, std::string* detail_gloss) {
  *detail_gloss = "exact";
  if (desc.has("detail_gloss") && desc.raw("detail_gloss").is_string())
    *detail_gloss = desc.raw("detail_gloss").get<std::string>();
  if (*detail_gloss != "exact" && *detail_gloss != "fit") return Verdict::quiet();  // parse_surface_maps names it
  *detail = desc.has("detail_normal_map") ? &desc.raw("detail_normal_map") : nullptr;
  if (!*detail) return {};
  const Json& d = **detail;
  std::string s, why;
  if (!d.is_object() || !json_string(d, "type", &s) || s != "image")
    why = "the detail normal map is not an \"image\" texture";
  else if (!json_string(d, "file", &s) || s.empty())
    return Verdict::quiet();  // its parser names the error
  else if (d.contains("channel"))
    why = "the detail normal map reads one channel";
  else if (json_string(d, "colorspace", &s) && s == "srgb")
    why = "the detail normal map is decoded as sRGB";
  else if (json_string(d, "filter", &s) && s == "closest")
    why = "the detail normal map reads level 0 only";
  if (!why.empty()) {
    if (desc.has("detail_gloss")) desc.warn("detail_gloss", "not applied: " + why);
    *detail = nullptr;
    return {};
  }
  plan->detail_normal_map = desc.get_object("detail_normal_map").get_path("file");
  if (!filtered_file_names(plan->detail_normal_map, 1.0, "", dir, &plan->out_detail_normal, &plan->out_detail_gloss))
    return Verdict::quiet();
  return {};
}

// The description the material is parsed from: the filtered chains in place of the map and the roughness.
std::shared_ptr<Json> filtered_description(const JsonObject& desc, NormalGlossFilteringPlan& plan, const Json* detail,
                                           const std::string& detail_gloss) {
  const Json& map = desc.raw("normal_map");
  auto json = std::make_shared<Json>(Json::object());
  Json& j = *json;
  for (const std::string& k : desc.keys())
    if (k != "normal_gloss_filtering" && k != "roughness" && k != "alpha" && k != "gloss" && k != "gloss_model" &&
        k != "normal_map_strength")
      j[k] = desc.raw(k);
  j["normal_map"]["file"] = plan.out_normal.string();
  j["normal_map"]["colorspace"] = "linear";
  const auto gloss_chain = [](const Json& source, const std::filesystem::path& file) {
    Json gloss = {{"type", "image"}, {"file", file.string()}, {"colorspace", "linear"}};
    for (const char* k : {"uv_scale", "uv_offset", "uv_rotation", "filter"})
      if (source.contains(k)) gloss[k] = source[k];
    return gloss;
  };
  // A WWII gloss: α = eq. (2) of the filtered value at each lookup; standard's roughness r = sqrt(α) of it.
  const char* out_key = plan.standard ? "roughness" : "gloss";
  j[out_key] = gloss_chain(map, plan.standard ? plan.out_roughness : plan.out_gloss);
  if (detail) {
    j["detail_normal_map"]["file"] = plan.out_detail_normal.string();
    j["detail_normal_map"]["colorspace"] = "linear";
    j[out_key] = {{"type", "wwii_gloss_combine"},
                  {"base", gloss_chain(map, plan.out_gloss)},
                  {"detail", gloss_chain(*detail, plan.out_detail_gloss)},
                  {"method", detail_gloss}};
    if (plan.standard) {
      j[out_key]["output"] = "roughness";
      plan.out_roughness.clear();  // the combination reads the gloss chains
    }
  }
  return json;
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
  const auto unless = [&](const Verdict& v) {
    if (v.kind == Verdict::Skip && given) desc.warn("normal_gloss_filtering", "not applied: " + v.why);
    return v.kind != Verdict::Go;
  };
  NormalGlossFilteringPlan plan;
  std::string file_key;  // what of the roughness the file names hash
  if (unless(check_normal_map(desc, &plan.strength)) || unless(plan_roughness(desc, &plan, &file_key)))
    return std::nullopt;
  if (plan.strength != 1.0) file_key += fmt::format("|strength {:.17g}", plan.strength);

  plan.normal_map = desc.get_object("normal_map").get_path("file");  // recorded as an input of the render
  // Absolute: the filtered files are named in the material's description, whose relative paths are read against
  // the scene's folder, and the cache folder is relative to the working directory.
  std::error_code ec;
  const std::filesystem::path dir = std::filesystem::absolute(ctx.textures()->convert_folder(), ec);
  if (ec) {
    unless(Verdict::skip("the texture cache's folder has no absolute path"));
    return std::nullopt;
  }
  if (!filtered_file_names(plan.normal_map, plan.gloss, file_key, dir, &plan.out_normal, &plan.out_gloss))
    return std::nullopt;
  if (!plan.roughness_map.empty()) plan.source_gloss = replace_suffix(plan.out_gloss, ".source-gloss.exr");
  if (plan.standard) plan.out_roughness = replace_suffix(plan.out_gloss, ".roughness.exr");
  const Json* detail = nullptr;
  std::string detail_gloss;
  if (unless(plan_detail(desc, dir, &plan, &detail, &detail_gloss))) return std::nullopt;
  plan.json = filtered_description(desc, plan, detail, detail_gloss);
  return plan;
}

namespace {

// Level 0 of the gloss a textured roughness gives, one WWII gloss a texel of the normal map: the image's channel
// times the scale, clamped to [0, 1], converted to α (roughness_to_alpha) and to gloss by eq. (2) inverted. A
// roughness image of another size is resampled bilinearly (wrapping, as the texture repeats) at the normal map's
// texel centres.
void write_source_gloss(const NormalGlossFilteringPlan& plan, const std::filesystem::path& out) {
  const ImageInfo map = probe_image(plan.normal_map);
  const Image r = read_image(plan.roughness_map);
  if (plan.roughness_channel >= r.channels)
    throw InputError(plan.roughness_map.string(), "",
                     fmt::format("has {} channel{}, no channel {}", r.channels, r.channels == 1 ? "" : "s",
                                 "rgba"[plan.roughness_channel]));
  const auto value = [&](int x, int y) {
    x = ((x % r.width) + r.width) % r.width, y = ((y % r.height) + r.height) % r.height;
    const float v =
        r.data[(size_t(y) * size_t(r.width) + size_t(x)) * size_t(r.channels) + size_t(plan.roughness_channel)];
    if (!std::isfinite(v))
      throw InputError(plan.roughness_map.string(), "", fmt::format("texel ({}, {}) is not a finite number", x, y));
    return std::clamp(static_cast<double>(v) * plan.roughness_scale, 0.0, 1.0);
  };
  Image g;
  g.width = map.width, g.height = map.height, g.channels = 1;
  g.data.resize(size_t(g.width) * size_t(g.height));
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      double v;
      if (r.width == g.width && r.height == g.height) {
        v = value(x, y);
      } else {
        const double fx = (x + 0.5) * r.width / g.width - 0.5, fy = (y + 0.5) * r.height / g.height - 0.5;
        const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
        const double tx = fx - x0, ty = fy - y0;
        v = (1 - ty) * ((1 - tx) * value(x0, y0) + tx * value(x0 + 1, y0)) +
            ty * ((1 - tx) * value(x0, y0 + 1) + tx * value(x0 + 1, y0 + 1));
      }
      const double alpha = roughness_to_alpha(plan.roughness_kind, v);
      g.data[size_t(y) * size_t(g.width) + size_t(x)] = static_cast<float>(
          plan.roughness_kind == RoughnessKind::Gloss ? v : wwii_alpha_to_gloss(alpha));  // Chan 2018 eq. (2)
    }
  write_mip_levels(out, {g});
}

// standard's roughness chain: r = sqrt(α) with α = eq. (2) of each filtered gloss texel, level by level.
void write_roughness_chain(const std::filesystem::path& gloss_file, const std::filesystem::path& out) {
  const int levels = probe_image(gloss_file).mip_levels;
  std::vector<Image> chain;
  for (int l = 0; l < levels; ++l) {
    Image level = read_mip_level(gloss_file, l);
    for (float& v : level.data) v = static_cast<float>(std::sqrt(wwii_gloss_to_alpha(v)));  // Chan 2018 eq. (2)
    chain.push_back(std::move(level));
  }
  write_mip_levels(out, chain);
}

bool nonempty_file(const std::filesystem::path& file) {
  std::error_code ec;
  return std::filesystem::file_size(file, ec) > 0 && !ec;
}

}  // namespace

void NormalGlossFilteringPlan::build(std::string* key) const {
  const auto step = [key](const std::string& k) {
    if (key) *key = k;
  };
  // One build at a time: the files' temporary names are unique per process, not per thread, and two materials may
  // share a map and a gloss (the second then finds the files).
  static std::mutex mutex;
  std::lock_guard lock(mutex);
  const auto build_one = [](const std::filesystem::path& in, double gloss, const std::filesystem::path& gloss_map,
                            const std::filesystem::path& normal, const std::filesystem::path& gloss_file,
                            double strength) {
    if (nonempty_file(normal) && nonempty_file(gloss_file)) return;
    std::error_code ec;
    std::filesystem::create_directories(normal.parent_path(), ec);
    NormalGlossFilterJob job;
    job.normal_map = in;
    job.gloss_value = gloss;
    job.gloss_map = gloss_map;
    job.strength = strength;
    job.out_normal = normal;
    job.out_gloss = gloss_file;
    job.model = ShortenedNormalModel::Macro;  // Chan 2018 Algorithm 2, as shipped
    filter_normal_gloss_files(job);
  };
  if (!source_gloss.empty() && !(nonempty_file(out_normal) && nonempty_file(out_gloss))) {
    step(roughness_key_name);
    std::error_code ec;
    std::filesystem::create_directories(source_gloss.parent_path(), ec);
    write_source_gloss(*this, source_gloss);
  }
  step("normal_map");
  build_one(normal_map, gloss, source_gloss, out_normal, out_gloss, strength);
  if (!out_roughness.empty() && !nonempty_file(out_roughness)) write_roughness_chain(out_gloss, out_roughness);
  step("detail_normal_map");
  if (!detail_normal_map.empty()) build_one(detail_normal_map, 1.0, {}, out_detail_normal, out_detail_gloss, 1.0);
}

}  // namespace kozu
