#include "media/homogeneous.h"

#include "core/json_reader.h"

namespace kozu {

float read_hg_phase(const JsonObject& desc) {
  if (!desc.has("phase")) return 0.0f;
  if (desc.raw("phase").is_string()) {
    desc.get_enum("phase", {"isotropic"});
    return 0.0f;
  }
  const JsonObject p = desc.get_object("phase");
  p.get_enum("type", {"hg"});
  const float g = p.get_float("g", {}, Range{-1.0, 1.0, true, true});
  p.finish();
  return g;
}

Deferred<Medium> HomogeneousMedium::parse(const JsonObject& desc) {
  const Rgb sigma_t = desc.get_rgb("density", Rgb(1.0f), Range::non_negative());
  const Rgb albedo = desc.get_rgb("albedo", Rgb(0.8f), Range::unit());
  const float g = read_hg_phase(desc);
  return std::make_unique<HomogeneousMedium>(sigma_t, albedo, g);
}

}  // namespace kozu
