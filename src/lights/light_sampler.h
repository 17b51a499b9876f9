// Chooses one light per next-event estimate with probability proportional to its power
// (average over RGB), through an alias table: O(1) to sample and to look up a light's pmf.
#pragma once

#include "core/distribution.h"
#include "lights/light.h"

#include <vector>

namespace kozu {

class LightSampler {
 public:
  LightSampler() = default;
  explicit LightSampler(const std::vector<const Light*>& lights);

  // nullptr when the scene has no lights. u_remapped receives a fresh uniform variate.
  const Light* sample(float u, float* pmf, float* u_remapped = nullptr) const;
  // 0 for a light not among those it was built from.
  float pmf(const Light* light) const {
    return light->index < slot_.size() && slot_[light->index] < lights_.size() ? table_.pmf(slot_[light->index]) : 0.0f;
  }
  bool empty() const { return lights_.empty(); }

 private:
  std::vector<const Light*> lights_;
  AliasTable table_;
  std::vector<uint32_t> slot_;  // per scene light index: its position in lights_, or past the end
};

}  // namespace kozu
