// The table that maps a light's JSON "type" to its parser (core/registry.h). Area lights are not here: they
// are a shape's "emission" (scene/scene_parse.cpp, areas built in scene/scene_build.cpp).
#include "lights/directional.h"
#include "lights/environment.h"
#include "lights/light.h"
#include "lights/point.h"
#include "lights/spot.h"

namespace kozu {

namespace {
constexpr RegistryEntry<Light> kLights[] = {
    {"directional", &DirectionalLight::parse},
    {"environment", &EnvironmentLight::parse},
    {"point", &PointLight::parse},
    {"spot", &SpotLight::parse},
};
}  // namespace

Deferred<Light> parse_light(const JsonObject& desc, std::string* type) {
  return parse_by_type(desc, kLights, {}, type);
}

}  // namespace kozu
