#include "lights/light_sampler.h"

namespace kozu {

LightSampler::LightSampler(const std::vector<const Light*>& lights) : lights_(lights) {
  std::vector<float> weights(lights.size());
  // p(light) proportional to its power (light_sampler.h); Walker's alias method makes sampling O(1).
  for (size_t i = 0; i < lights.size(); ++i) weights[i] = std::max(0.0f, average(lights[i]->power()));
  table_ = AliasTable(weights);
  for (size_t i = 0; i < lights.size(); ++i) {
    if (lights[i]->index >= slot_.size()) slot_.resize(lights[i]->index + 1, 0xffffffffu);
    slot_[lights[i]->index] = static_cast<uint32_t>(i);
  }
}

const Light* LightSampler::sample(float u, float* pmf, float* u_remapped) const {
  if (lights_.empty()) return nullptr;
  if (lights_.size() == 1) {
    *pmf = 1.0f;
    if (u_remapped) *u_remapped = u;
    return lights_[0];
  }
  const uint32_t i = table_.sample(u, u_remapped);
  *pmf = table_.pmf(i);
  return lights_[i];
}

}  // namespace kozu
