// The one table that maps a material's JSON "type" to its constructor.
#include "core/json_reader.h"
#include "materials/conductor.h"
#include "materials/dielectric.h"
#include "materials/diffuse.h"
#include "materials/plastic.h"
#include "materials/subsurface.h"

#include <fmt/format.h>

namespace kozu {

namespace {
struct MaterialEntry {
  const char* type;
  std::unique_ptr<Material> (*create)(const JsonObject&);
};
constexpr MaterialEntry kMaterials[] = {
    {"diffuse", &DiffuseMaterial::create},
    {"conductor", &ConductorMaterial::create},
    {"dielectric", &DielectricMaterial::create},
    {"plastic", &PlasticMaterial::create},
    {"subsurface", &SubsurfaceMaterial::create},
};
}  // namespace

std::unique_ptr<Material> make_material(const JsonObject& desc) {
  std::vector<std::string> types;
  for (const auto& e : kMaterials) types.emplace_back(e.type);
  const std::string type = desc.get_enum("type", types);
  for (const auto& e : kMaterials) {
    if (type == e.type) {
      auto m = e.create(desc);
      desc.finish();
      return m;
    }
  }
  return nullptr;  // unreachable: get_enum validated the type
}

}  // namespace kozu
