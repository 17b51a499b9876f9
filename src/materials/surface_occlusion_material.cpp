#include "materials/surface_occlusion_material.h"

#include "core/error.h"
#include "core/file_io.h"
#include "core/memory.h"
#include "core/temp_files.h"
#include "io/image_io.h"
#include "materials/bsdf.h"
#include "materials/material.h"
#include "materials/roughness.h"
#include "materials/specular_occlusion_table.h"
#include "textures/height_from_normals.h"
#include "textures/surface_occlusion.h"
#include "textures/texture_parse.h"

#include <fmt/format.h>

#include <cmath>
#include <mutex>

namespace kozu {

namespace {

// Bumped when the visibility build or its file changes, so that old files are not reused.
constexpr int kBuildVersion = 1;
// Working memory per texel of the build: the height solver's chain and scratch (as `kozu texture occlusion`
// counts it), the image as floats, the slopes and the visibility.
constexpr double kBuildBytesPerTexel = 16 * 4.0 / 3.0 + 24 + 16 + 8 + 8;

}  // namespace

float SurfaceOcclusion::cone_cos(const SurfaceInteraction& si) const {
  const Rgb v = visibility_->eval(texture_query(si));
  return std::sqrt(std::clamp(1.0f - v.r, 0.0f, 1.0f));  // Chan 2018 eq. (56)
}

float SurfaceOcclusion::indirect(float cone_cos, float n_dot_v, float n_dot_l, uint32_t flags) const {
  if (flags & kBsdfTransmission) return 1.0f;
  if (flags & kBsdfSpecular) return hard_cone(cone_cos, n_dot_l);  // a Dirac lobe: its one direction
  if ((flags & kBsdfGlossy) && s_.specular == Specular::Off) return 1.0f;
  if ((flags & kBsdfGlossy) && s_.gloss >= 0.0f) {
    float c = cone_cos;
    if (s_.specular == Specular::Game) c = game_cone_cos(cone_cos, n_dot_v, s_.gloss, nullptr);  // eqs. (59)–(60)
    return specular_occlusion(n_dot_v, s_.gloss, c);                                             // Chan 2018 §4.7
  }
  // A cosine lobe's fraction inside the equal-area cone is V itself (eq. 54); eq. (49) adds what the occluders of
  // albedo ρ send back.
  const float v = 1.0f - cone_cos * cone_cos;
  return float(adjusted_visibility(v, s_.albedo, OcclusionAdjustment::Interreflection));
}

void SurfaceOcclusionBuild::build() const {
  // One build at a time: temporary names are unique per process, and two materials may share a map.
  static std::mutex mutex;
  std::lock_guard lock(mutex);
  std::error_code ec;
  if (std::filesystem::file_size(out, ec) > 0 && !ec) return;
  const ImageInfo info = probe_image(normal_map);
  const double need = double(info.width) * info.height * kBuildBytesPerTexel;
  const MemoryLimit limit = memory_limit();
  const double left = memory_left(limit);
  if (limit.bytes > 0 && need > left)
    throw InputError(
        normal_map.string(), "",
        fmt::format("surface occlusion: {} x {} texels need about {} of memory, {} is left ({})", info.width,
                    info.height, format_bytes(need), format_bytes(std::max(left, 0.0)), limit.source));
  const Image img = read_image(normal_map);
  if (img.channels < 3)
    throw InputError(
        normal_map.string(), "",
        fmt::format("surface occlusion: a normal map needs three channels, this image has {}", img.channels));
  for (float x : img.data)
    if (!std::isfinite(x)) throw InputError(normal_map.string(), "", "surface occlusion: a texel is not finite");
  // Chan 2018 Algorithm 5 (height) and eq. (43) (visibility), with `kozu texture occlusion`'s defaults.
  const SlopeField g = normal_slopes(img.data.data(), img.width, img.height, img.channels, flip_y);
  const HeightField hf = height_from_slopes(g);
  OcclusionOptions o;
  o.height_scale = height_scale;
  const std::vector<float> v = visibility(hf, o);
  std::filesystem::create_directories(out.parent_path(), ec);
  write_single_channel_exr(out, hf.width, hf.height, v,
                           {{"kozu:content", "cosine-weighted visibility (Chan 2018 eq. 43), unadjusted"}});
}

std::unique_ptr<const SurfaceOcclusion> SurfaceOcclusionDesc::load() {
  if (build) build->build();
  // The specular table is computed in the load phase, not by the first path that needs it.
  if (settings.specular != SurfaceOcclusion::Specular::Off && settings.gloss >= 0.0f) SpecularOcclusionTable::get();
  return std::make_unique<SurfaceOcclusion>(ao.take(), settings);
}

std::shared_ptr<SurfaceOcclusionDesc> parse_surface_occlusion(const JsonObject& desc, const JsonObject& original,
                                                              const std::function<TextureCache*()>& textures) {
  constexpr const char* kKey = "surface_occlusion";
  if (!desc.has(kKey)) return nullptr;
  const Json& raw = desc.raw(kKey);
  if (raw.is_boolean() && !raw.get<bool>()) return nullptr;
  if (!raw.is_boolean() && !raw.is_object())
    desc.fail(kKey, "expected true, false or an object {\"mode\": \"cone\" | \"off\", ...}");
  if (!desc.has("normal_map")) desc.fail(kKey, "'surface_occlusion' needs a 'normal_map'");
  auto d = std::make_shared<SurfaceOcclusionDesc>();
  d->json_path = desc.path_of(kKey);
  std::optional<JsonObject> so;
  if (raw.is_object()) {
    so.emplace(desc.get_object(kKey));
    if (so->get_enum("mode", {"cone", "off"}, std::string("cone")) == "off") {
      for (const std::string& k : so->keys()) so->ignore(k);  // an "off" block may keep its settings
      return nullptr;
    }
    d->settings.direct = so->get_enum("direct", {"smooth", "hard"}, std::string("smooth")) == "smooth"
                             ? SurfaceOcclusion::Direct::Smooth
                             : SurfaceOcclusion::Direct::Hard;
    const std::string spec = so->get_enum("specular", {"table", "game", "off"}, std::string("table"));
    d->settings.specular = spec == "table"  ? SurfaceOcclusion::Specular::Table
                           : spec == "game" ? SurfaceOcclusion::Specular::Game
                                            : SurfaceOcclusion::Specular::Off;
    d->settings.albedo = so->get_float("albedo", 0.0f, Range::unit());
    if (so->has("gloss")) d->settings.gloss = so->get_float("gloss", {}, Range::unit());
  }

  // The gloss the specular table is read at: the material's own plain roughness (materials/roughness.h's
  // conversions), unless given. A diffuse material has no glossy lobe.
  const std::string type =
      original.has("type") && original.raw("type").is_string() ? original.raw("type").get<std::string>() : "";
  if (d->settings.gloss < 0.0f && type != "diffuse" && d->settings.specular != SurfaceOcclusion::Specular::Off) {
    const char* key = nullptr;
    for (const char* k : {"roughness", "alpha", "gloss"})
      if (original.has(k) && original.raw(k).is_number()) key = k;
    if (!key)
      desc.fail(kKey,
                "the specular occlusion table needs the material's gloss, and its roughness is not one plain number: "
                "give \"gloss\" here, or \"specular\": \"off\"");
    const float x = std::clamp(original.raw(key).get<float>(), 0.0f, 1.0f);
    const bool aw = std::string_view(key) == "gloss" && original.has("gloss_model") &&
                    original.raw("gloss_model").is_string() && original.raw("gloss_model") == "aw";
    const float alpha = std::string_view(key) == "roughness" ? x * x
                        : std::string_view(key) == "alpha"   ? x
                        : aw                                 ? gloss_to_alpha(x, GlossModel::AdvancedWarfare)
                                                             : gloss_to_alpha(x);
    d->settings.gloss = std::string_view(key) == "gloss" && !aw ? x : alpha_to_gloss(alpha);  // Chan 2018 eq. (2)
  }

  const TextureParseContext tex{TextureUse::Data, textures, Range::unit()};
  if (so && so->has("ao")) {
    d->ao = parse_texture(*so, "ao", tex);
  } else {
    // Computed from the scene's own normal map (not a filtered chain that replaced it).
    const Json& map = original.raw("normal_map");
    std::string s;
    if (!map.is_object() || !json_string(map, "type", &s) || s != "image" || map.contains("channel") ||
        !json_string(map, "file", &s) || s.empty())
      desc.fail(kKey, "computing the visibility needs an \"image\" normal map of three channels: give \"ao\"");
    if (!textures) desc.fail(kKey, "image textures are not available here: give \"ao\" as a number");
    SurfaceOcclusionBuild b;
    b.normal_map = original.get_object("normal_map").get_path("file");
    b.flip_y = original.has("normal_map_convention") && original.raw("normal_map_convention").is_string() &&
               original.raw("normal_map_convention") == "directx";
    if (original.has("normal_map_strength") && original.raw("normal_map_strength").is_number())
      b.height_scale = original.raw("normal_map_strength").get<float>();
    std::error_code ec;
    const auto size = std::filesystem::file_size(b.normal_map, ec);
    if (ec) desc.fail(kKey, fmt::format("{}: cannot read the normal map: {}", b.normal_map.string(), ec.message()));
    const auto mtime = std::filesystem::last_write_time(b.normal_map, ec).time_since_epoch().count();
    const std::filesystem::path absolute = std::filesystem::absolute(b.normal_map, ec);
    const size_t hash =
        std::hash<std::string>{}(fmt::format("{}|{}|{}|{}|{:.9g}|r32|d16|{}", absolute.string(), size,
                                             static_cast<long long>(mtime), b.flip_y, b.height_scale, kBuildVersion));
    // Absolute: the synthesized texture's "file" is resolved against the scene's folder, as any scene path is.
    b.out = std::filesystem::absolute(textures()->convert_folder(), ec) /
            fmt::format("{}-{:016x}.ao.exr", b.normal_map.stem().string(), hash);
    Json ao = {{"type", "image"}, {"file", b.out.string()}, {"colorspace", "linear"}};
    for (const char* k : {"uv_scale", "uv_offset", "uv_rotation", "filter"})
      if (map.contains(k)) ao[k] = map[k];
    d->json = std::make_shared<Json>(Json{{"ao", ao}});
    d->ao = parse_texture(JsonObject(*d->json, d->json_path, desc.source_ptr()), "ao", tex);
    d->build = b;
  }
  if (so) so->finish();
  return d;
}

}  // namespace kozu
