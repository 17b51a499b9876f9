#include "scene/scene.h"

#include "core/input_bounds.h"

#include <fmt/format.h>

#include <stdexcept>

namespace kozu {

void Scene::build() {
  accel_ = std::make_unique<EmbreeScene>(shapes);
  set_bounds_and_lights(true);
}

void Scene::pose_shapes(double time) {
  if (animated_shapes.empty()) return;
  std::vector<const Shape*> moved;
  for (const AnimatedShape& a : animated_shapes) {
    a.shape->set_pose(animation.shapes[a.track].transform_at(time) * a.unplace);
    Vec3 lo(kInfinity), hi(-kInfinity);
    a.shape->bounds(lo, hi);
    // Keys are bounded, but a large shape scaled up can still leave the range Embree and kozu's offsets handle.
    if (!is_finite(lo) || !is_finite(hi) || !within_bounds(lo) || !within_bounds(hi))
      throw std::invalid_argument(fmt::format("'{}' leaves kozu's coordinate range (±{:g}) at t = {:.4g} s",
                                              animation.shapes[a.track].name, kMaxCoordinate, time));
    for (Light* light : a.lights) {
      light->refit();
      // A scaled-up emitter's power grows with its area: it must stay within the range a still's is held to.
      const Rgb power = light->power();
      if (!is_finite(power) || max_component(power) > kMaxLightPower)
        throw std::invalid_argument(fmt::format(
            "'{}' emits {:.3g} W at t = {:.4g} s, beyond kozu's range (at most {:g}); lower its emission or its keys' "
            "scale",
            animation.shapes[a.track].name, is_finite(power) ? max_component(power) : kInfinity, time, kMaxLightPower));
    }
    moved.push_back(a.shape);
  }
  accel_->update(moved);
  set_bounds_and_lights(false);  // the light sampler anew: a scaled emitter's power changes
}

void Scene::set_bounds_and_lights(bool all_lights) {
  Vec3 lo(kInfinity), hi(-kInfinity);
  for (const auto& s : shapes) s->bounds(lo, hi);
  if (shapes.empty()) {
    lo = hi = camera.position();
  }
  center_ = 0.5f * (lo + hi);
  radius_ = std::max(0.5f * glm::length(hi - lo), 1e-3f);
  std::vector<const Light*> all;
  infinite_lights_.clear();
  for (size_t i = 0; i < lights.size(); ++i) {
    lights[i]->index = static_cast<uint32_t>(i);
    if (all_lights || lights[i]->is_infinite()) lights[i]->preprocess(center_, radius_);
    all.push_back(lights[i].get());
    if (lights[i]->is_infinite()) infinite_lights_.push_back(lights[i].get());
  }
  light_sampler_ = LightSampler(all);
  light_tree_ = LightTree(all);
  std::vector<const Light*> aimed;
  Vec3 aim;
  for (const Light* l : all)
    if (l->aim_point(&aim)) aimed.push_back(l);
  aim_sampler_ = LightSampler(aimed);
}

size_t Scene::triangle_count() const {
  size_t n = 0;
  for (const auto& s : shapes) {
    if (dynamic_cast<const TriangleMesh*>(s.get())) n += s->primitive_count();
    // An instance's triangles count once per instance: the triangles the image shows, not those stored.
    if (const auto* inst = dynamic_cast<const Instance*>(s.get()))
      for (const auto& o : inst->object().shapes())
        if (dynamic_cast<const TriangleMesh*>(o.get())) n += o->primitive_count();
  }
  return n;
}

void Scene::set_media_view() {
  const RayCone pixel = camera.pixel_cone();
  view_warnings.clear();
  for (auto& m : media) {
    m->set_view(camera.position(), pixel.width, pixel.spread);
    if (std::string w = m->view_warning(); !w.empty()) view_warnings.push_back(std::move(w));
  }
}

}  // namespace kozu
