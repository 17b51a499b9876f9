// The one table that maps a medium's JSON "type" to its constructor.
#include "core/json_reader.h"
#include "media/grid_medium.h"
#include "media/homogeneous.h"
#include "media/sggx_medium.h"

namespace kozu {

namespace {
struct MediumEntry {
  const char* type;
  std::unique_ptr<Medium> (*create)(const JsonObject&);
};
constexpr MediumEntry kMedia[] = {
    {"homogeneous", &HomogeneousMedium::create},
    {"grid", &GridMedium::create},
    {"sggx", &SggxMedium::create},
};
}  // namespace

std::unique_ptr<Medium> make_medium(const JsonObject& desc) {
  std::vector<std::string> types;
  for (const auto& e : kMedia) types.emplace_back(e.type);
  const std::string type = desc.get_enum("type", types);
  for (const auto& e : kMedia) {
    if (type == e.type) {
      auto m = e.create(desc);
      desc.finish();
      return m;
    }
  }
  return nullptr;  // unreachable: get_enum validated the type
}

}  // namespace kozu
