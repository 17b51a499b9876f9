#include "materials/conductor.h"

#include "io/json_reader.h"
#include "materials/fresnel.h"
#include "materials/metal_data.h"

#include <fmt/format.h>

namespace kozu {

BsdfSample SmoothConductorBsdf::sample(const Vec3& wo, float, const Vec2&, TransportMode) const {
  BsdfSample s;
  if (wo.z == 0.0f) return s;
  s.wi = Vec3(-wo.x, -wo.y, wo.z);
  s.f = perfect_ ? Rgb(1.0f) : fresnel_conductor(abs_cos_theta(wo), eta_, k_);
  s.pdf = 1.0f;
  s.flags = kBsdfReflection | kBsdfSpecular;
  return s;
}

std::unique_ptr<Material> ConductorMaterial::create(const JsonObject& desc) {
  const bool has_metal = desc.has("metal");
  const bool has_eta = desc.has("eta") || desc.has("k");
  if (has_metal && has_eta) desc.fail("metal", "give either 'metal' or 'eta'/'k', not both");
  if (has_metal) {
    const std::string name = desc.get_string("metal");
    const MetalIor* m = find_metal(name);
    if (!m) {
      std::string list;
      for (const auto& e : kMetals) list += (list.empty() ? "" : ", ") + std::string(e.symbol);
      desc.fail("metal", fmt::format("unknown metal '{}' (known: {})", name, list));
    }
    return std::make_unique<ConductorMaterial>(m->eta, m->k, false);
  }
  if (has_eta) {
    const Rgb eta = desc.get_rgb("eta", {}, Range::positive());
    const Rgb k = desc.get_rgb("k", Rgb(0.0f), Range::non_negative());
    return std::make_unique<ConductorMaterial>(eta, k, false);
  }
  return std::make_unique<ConductorMaterial>(Rgb(1.0f), Rgb(0.0f), true);
}

const Bsdf* ConductorMaterial::bsdf(const SurfaceInteraction&, Arena& arena) const {
  return arena.make<SmoothConductorBsdf>(eta_, k_, perfect_);
}

}  // namespace kozu
