// The table that maps a material's JSON "type" to its parser (core/registry.h).
#include "materials/conductor.h"
#include "materials/dielectric.h"
#include "materials/diffuse.h"
#include "materials/plastic.h"
#include "materials/subsurface.h"

namespace kozu {

namespace {
constexpr RegistryEntry<Material, const MaterialParseContext&> kMaterials[] = {
    {"diffuse", &DiffuseMaterial::parse},       {"conductor", &ConductorMaterial::parse},
    {"dielectric", &DielectricMaterial::parse}, {"plastic", &PlasticMaterial::parse},
    {"subsurface", &SubsurfaceMaterial::parse},
};
}  // namespace

bool has_material_type(std::string_view type) { return registry_has(kMaterials, type); }

Deferred<Material> parse_material(const JsonObject& desc, const MaterialParseContext& ctx) {
  return parse_by_type(desc, kMaterials, {}, nullptr, ctx);
}

}  // namespace kozu
