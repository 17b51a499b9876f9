// The table that maps a material's JSON "type" to its parser (core/registry.h).
#include "core/error.h"
#include "materials/conductor.h"
#include "materials/dielectric.h"
#include "materials/diffuse.h"
#include "materials/normal_gloss_filtering.h"
#include "materials/plastic.h"
#include "materials/standard.h"
#include "materials/subsurface.h"
#include "textures/texture_parse.h"

#include <fmt/format.h>

#include <optional>

namespace kozu {

namespace {
constexpr RegistryEntry<Material, const MaterialParseContext&> kMaterials[] = {
    {"diffuse", &DiffuseMaterial::parse},       {"conductor", &ConductorMaterial::parse},
    {"dielectric", &DielectricMaterial::parse}, {"plastic", &PlasticMaterial::parse},
    {"subsurface", &SubsurfaceMaterial::parse}, {"standard", &StandardMaterial::parse},
};

// The keys every surface material accepts, read before the type's own keys (so finish() counts them as read).
struct SurfaceMapsDesc {
  std::optional<Deferred<Texture>> normal_map;
  float normal_strength = 1.0f;
  bool normal_flip_y = false;
  std::optional<Deferred<Texture>> detail_normal_map;
  DetailBlend detail_blend = DetailBlend::BlendXY;
  std::optional<Deferred<Texture>> bump_map;
  float bump_scale = 1.0f;
  std::optional<Deferred<Texture>> opacity;
  bool any() const { return normal_map || bump_map || opacity; }
};

SurfaceMapsDesc parse_surface_maps(const JsonObject& desc, const MaterialParseContext& ctx) {
  SurfaceMapsDesc m;
  if (desc.has("normal_map")) {
    m.normal_map = parse_texture(desc, "normal_map", {TextureUse::Data, ctx.textures, Range::unit()});
    m.normal_strength = desc.get_float("normal_map_strength", 1.0f, Range::non_negative());
    m.normal_flip_y = desc.get_enum("normal_map_convention", {"opengl", "directx"}, std::string("opengl")) == "directx";
    // A detail normal map, blended into the base in tangent space (materials/detail_normal_blend.h).
    if (desc.has("detail_normal_map")) {
      m.detail_normal_map = parse_texture(desc, "detail_normal_map", {TextureUse::Data, ctx.textures, Range::unit()});
      m.detail_blend = desc.get_enum("detail_blend", {"blendxy", "rnm"}, std::string("blendxy")) == "rnm"
                           ? DetailBlend::Rnm
                           : DetailBlend::BlendXY;
      // How a filtered detail map's gloss combines with the base's (materials/normal_gloss_filtering.h reads it).
      desc.get_enum("detail_gloss", {"exact", "fit"}, std::string("exact"));
    } else {
      for (const char* key : {"detail_blend", "detail_gloss"})
        if (desc.has(key)) desc.fail(key, fmt::format("'{}' needs a 'detail_normal_map'", key));
    }
  } else {
    for (const char* key :
         {"normal_map_strength", "normal_map_convention", "detail_normal_map", "detail_blend", "detail_gloss"})
      if (desc.has(key)) desc.fail(key, fmt::format("'{}' needs a 'normal_map'", key));
  }
  if (desc.has("bump_map")) {
    if (m.normal_map) desc.fail("bump_map", "give either 'normal_map' or 'bump_map', not both");
    m.bump_map = parse_texture(desc, "bump_map", {TextureUse::Data, ctx.textures, Range{}});
    m.bump_scale = desc.get_float("bump_scale", 1.0f, Range::closed(-1e6, 1e6));
  } else if (desc.has("bump_scale")) {
    desc.fail("bump_scale", "'bump_scale' needs a 'bump_map'");
  }
  // A plain 1 is the default (opaque): no mask, no accelerator filter.
  if (desc.has("opacity") && !(desc.raw("opacity").is_number() && desc.get_float("opacity", {}, Range::unit()) == 1.0f))
    m.opacity = parse_texture(desc, "opacity", {TextureUse::Data, ctx.textures, Range::unit()});
  return m;
}

}  // namespace

Deferred<Material> parse_material(const JsonObject& original, const MaterialParseContext& ctx) {
  // Normal and gloss mip filtering (materials/normal_gloss_filtering.h): the material is parsed from a description
  // whose normal map and roughness are the filtered chains, built in the load job before the textures are read.
  std::optional<NormalGlossFilteringPlan> plan = plan_normal_gloss_filtering(original, ctx);
  std::optional<JsonObject> filtered;
  if (plan) filtered.emplace(*plan->json, original.path(), original.source_ptr());
  const JsonObject& desc = plan ? *filtered : original;
  auto maps = std::make_shared<SurfaceMapsDesc>(parse_surface_maps(desc, ctx));
  auto occlusion = parse_surface_occlusion(desc, original, ctx.textures);  // materials/surface_occlusion_material.h
  Deferred<Material> base = parse_by_type(desc, kMaterials, {}, nullptr, ctx);
  if (!maps->any()) return base;
  auto shared_base = std::make_shared<Deferred<Material>>(std::move(base));
  auto shared_plan = plan ? std::make_shared<NormalGlossFilteringPlan>(std::move(*plan)) : nullptr;
  return Deferred<Material>([maps, shared_base, shared_plan, occlusion, original]() -> std::unique_ptr<Material> {
    if (shared_plan) {
      std::string key = "normal_map";  // the key whose file a failure names
      try {
        shared_plan->build(&key);
      } catch (const InputError& e) {
        original.fail(key, e.what());
      }
    }
    std::unique_ptr<Material> m = shared_base->take();
    if (maps->normal_map)
      m->normal_map = std::make_unique<NormalMap>(maps->normal_map->take(), maps->normal_strength, maps->normal_flip_y,
                                                  maps->detail_normal_map ? maps->detail_normal_map->take() : nullptr,
                                                  maps->detail_blend);
    if (maps->bump_map) m->bump_map = std::make_unique<BumpMap>(maps->bump_map->take(), maps->bump_scale);
    if (maps->opacity) m->opacity = std::make_unique<TextureOpacity>(maps->opacity->take());
    if (occlusion) m->surface_occlusion = occlusion->load();
    return m;
  });
}

}  // namespace kozu
