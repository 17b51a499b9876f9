#include "textures/texture_parse.h"

#include "core/error.h"
#include "io/image_io.h"
#include "textures/checker_texture.h"
#include "textures/image_texture.h"
#include "textures/wwii_gloss_combine.h"

#include <fmt/format.h>

namespace kozu {

namespace {

Vec2 get_vec2(const JsonObject& o, std::string_view key, const Vec2& def, const Range& range) {
  if (!o.has(key)) return def;
  const JsonArray a = o.get_array(key);
  if (a.size() != 2) a.fail(fmt::format("expected [{0}u, {0}v], 2 numbers", key == "uv_offset" ? "o" : "s"));
  return Vec2(static_cast<float>(a.number(0, range)), static_cast<float>(a.number(1, range)));
}

Deferred<Texture> parse_constant(const JsonObject& t, const TextureParseContext& ctx) {
  return std::make_unique<ConstantTexture>(t.get_rgb("value", {}, ctx.range));
}

Deferred<Texture> parse_checker(const JsonObject& t, const TextureParseContext& ctx) {
  const Vec2 scale = get_vec2(t, "scale", Vec2(8.0f), Range{0.0, 1e6, true, false});
  const Rgb a = t.get_rgb("a", Rgb(0.8f), ctx.range), b = t.get_rgb("b", Rgb(0.2f), ctx.range);
  return std::make_unique<CheckerTexture>(scale, a, b);
}

Deferred<Texture> parse_image(const JsonObject& t, const TextureParseContext& ctx) {
  if (!ctx.cache) t.fail("image textures are not available here");
  const std::filesystem::path file = t.get_path("file");
  const std::string cs = t.get_enum("colorspace", {"auto", "srgb", "linear"}, std::string("auto"));
  const ColorSpace space = cs == "srgb" ? ColorSpace::Srgb : cs == "linear" ? ColorSpace::Linear : ColorSpace::Auto;
  ImageTexture::Options opt;
  if (t.has("channel")) {
    const std::string c = t.get_enum("channel", {"r", "g", "b", "a"});
    opt.channel = static_cast<int>(std::string_view("rgba").find(c[0]));
  }
  opt.uv_scale = get_vec2(t, "uv_scale", Vec2(1.0f), Range{-1e6, 1e6});
  opt.uv_offset = get_vec2(t, "uv_offset", Vec2(0.0f), Range{-1e6, 1e6});
  opt.uv_rotation = t.get_float("uv_rotation", 0.0f, Range{-1e6, 1e6});
  const std::string filter = t.get_enum("filter", {"ewa", "trilinear", "closest"}, std::string("ewa"));
  opt.filter = filter == "closest"     ? ImageTexture::Filter::Closest
               : filter == "trilinear" ? ImageTexture::Filter::Trilinear
                                       : ImageTexture::Filter::Ewa;
  opt.scale = t.get_rgb("scale", Rgb(1.0f), Range::non_negative());
  if (t.has("threshold")) opt.threshold = t.get_float("threshold", {}, Range::non_negative());
  TextureCache* cache = ctx.cache();
  const TextureUse use = ctx.use;
  return Deferred<Texture>([=]() -> std::unique_ptr<Texture> {
    std::filesystem::path prepared;
    std::string warning;
    try {
      prepared = cache->prepare(file, space, use, &warning);
    } catch (const InputError& e) {
      t.fail("file", e.what());
    }
    if (!warning.empty()) {
      std::lock_guard lock(image_warning_mutex());
      t.warn("file", warning);
    }
    // A channel the file lacks would read as 0 everywhere: refuse it by name.
    if (opt.channel >= 0) {
      const ImageInfo info = probe_image(prepared);
      if (opt.channel >= info.channels)
        t.fail("channel", fmt::format("{} has {} channel{}", file.filename().string(), info.channels,
                                      info.channels == 1 ? "" : "s"));
    }
    return std::make_unique<ImageTexture>(*cache, prepared, opt);
  });
}

constexpr RegistryEntry<Texture, const TextureParseContext&> kTextures[] = {
    {"image", &parse_image},
    {"checker", &parse_checker},
    {"constant", &parse_constant},
    {"wwii_gloss_combine", &parse_wwii_gloss_combine},
};

}  // namespace

Deferred<Texture> parse_texture(const JsonObject& parent, std::string_view key, const TextureParseContext& ctx) {
  if (!parent.raw(key).is_object()) return std::make_unique<ConstantTexture>(parent.get_rgb(key, {}, ctx.range));
  return parse_by_type(parent.get_object(key), kTextures, {}, nullptr, ctx);
}

}  // namespace kozu
