// The table that maps a medium's JSON "type" to its parser (core/registry.h).
#include "media/grid_medium.h"
#include "media/homogeneous.h"
#include "media/sggx_medium.h"

namespace kozu {

namespace {
constexpr RegistryEntry<Medium> kMedia[] = {
    {"homogeneous", &HomogeneousMedium::parse},
    {"grid", &GridMedium::parse},
    {"sggx", &SggxMedium::parse},
};
}  // namespace

Deferred<Medium> parse_medium(const JsonObject& desc) { return parse_by_type(desc, kMedia); }

}  // namespace kozu
