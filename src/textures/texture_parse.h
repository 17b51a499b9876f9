// Textureable keys: a material parameter that takes a number or [r, g, b] also takes a texture object,
//   {"type": "image", ...}    textures/image_texture.h
//   {"type": "checker", ...}  textures/checker_texture.h
//   {"type": "constant", "value": v}
//   {"type": "wwii_gloss_combine", ...}  textures/wwii_gloss_combine.h (a base and a detail gloss, Chan 2018 eq. 34)
// parsed through the texture table (core/registry.h). Image files are prepared (converted to tiled mip-mapped
// textures) by the returned job, in the scene's load phase.
#pragma once

#include "core/registry.h"
#include "textures/texture.h"
#include "textures/texture_cache.h"

#include <functional>
#include <memory>
#include <string_view>

namespace kozu {

struct TextureParseContext {
  TextureUse use = TextureUse::Color;
  std::function<TextureCache*()> cache;  // for image textures (called while parsing); empty: refused
  Range range = Range::non_negative();   // what constant values (and checker colours) must satisfy
};

// The texture of parent[key]; a plain value becomes a ConstantTexture. The key must be present.
Deferred<Texture> parse_texture(const JsonObject& parent, std::string_view key, const TextureParseContext& ctx);

}  // namespace kozu
