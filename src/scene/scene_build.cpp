// The scene loader's build phase (scene_loader.h): the scene's models, the shapes with their area lights, the
// lights and the accelerator, from a loaded SceneDesc.
#include "scene/scene_desc.h"

#include "core/input_bounds.h"
#include "geometry/instance.h"
#include "lights/area.h"

#include <algorithm>
#include <stdexcept>

namespace kozu::scene_load {

namespace {

// The area lights of an emitting shape: one for a sphere, one for a quad or polygon (kept whole), one per
// triangle of a mesh.
void add_area_lights(Shape& shape, const ShapeDesc& d, Scene& scene) {
  if (auto* sphere = dynamic_cast<Sphere*>(&shape)) {
    scene.lights.push_back(std::make_unique<SphereLight>(sphere, d.emission, d.two_sided));
    shape.lights.push_back(scene.lights.back().get());
    return;
  }
  auto* mesh = static_cast<TriangleMesh*>(&shape);
  if (d.type == "quad" || d.type == "polygon") {
    std::unique_ptr<Texture> texture = d.emission_texture ? d.emission_texture->take() : nullptr;
    if (texture && texture->is_constant())
      scene.lights.push_back(std::make_unique<PolygonLight>(mesh, texture->eval({}), d.two_sided));
    else
      scene.lights.push_back(std::make_unique<PolygonLight>(mesh, d.emission, d.two_sided, std::move(texture)));
    shape.lights.push_back(scene.lights.back().get());
    return;
  }
  for (uint32_t p = 0; p < mesh->primitive_count(); ++p) {
    scene.lights.push_back(std::make_unique<TriangleLight>(mesh, p, d.emission, d.two_sided));
    shape.lights.push_back(scene.lights.back().get());
  }
}

// The emission that makes the shape emit the power sd.emission holds (docs/lights.md "Light power in watts"):
// L = Phi / (pi A), halved when both sides emit, the inverse of the area lights' power().
Rgb power_to_emission(const Shape& shape, const ShapeDesc& sd) {
  double area = 0.0;
  for (uint32_t p = 0; p < shape.primitive_count(); ++p) area += double(shape.primitive_area(p));
  const double per_unit = M_PI * area * (sd.two_sided ? 2.0 : 1.0);
  const std::string path = json_pointer_append(sd.json_path, "power");
  const double radiance = double(max_component(sd.emission)) / per_unit;
  if (!(per_unit > 0.0))
    throw InputError(sd.file, path, "the shape has no area, so it cannot emit a power: give 'emission'");
  if (!(radiance <= kMaxRadiance))
    throw InputError(sd.file, path,
                     fmt::format("{:g} W over an area of {:.3g} is a radiance of {:.3g}, beyond kozu's range (at most "
                                 "{:g})",
                                 double(max_component(sd.emission)), area, radiance, kMaxRadiance));
  return Rgb(Vec3d(sd.emission) / per_unit);
}

// A shape's material, media, cut-out and tangents, and the warnings about it.
void dress(Shape* shape, const ShapeDesc& sd, std::optional<size_t> material, const SceneDesc& d, Scene& scene) {
  shape->material = material ? d.materials.built[*material] : nullptr;
  // An open boundary lets paths into a medium or a subsurface material that never find the way out (or out of
  // one they never entered): not an error (a ground plane may rightly bound an atmosphere), but said.
  const bool subsurface = shape->material && shape->material->has_subsurface();
  if (sd.interior || sd.exterior || subsurface)
    if (const size_t open = shape->open_edges(); open > 0)
      scene.warnings.push_back(InputError::format(
          sd.file, sd.json_path,
          fmt::format("the shape {} but is not closed ({} edge{} on one triangle only): paths can cross it "
                      "once and end up inside without a way out; close the mesh",
                      subsurface ? "has a subsurface material" : "bounds a medium", open, open == 1 ? "" : "s")));
  if (shape->material && shape->material->perturbs_shading()) shape->prepare_tangents();
  if (shape->material && shape->material->opacity) {
    // Area lights sample points on the whole surface: holes would still emit.
    if (!is_black(sd.emission))
      throw InputError(sd.file, json_pointer_append(sd.json_path, "material"),
                       fmt::format("material '{}' has an opacity cut-out, which an emitting shape cannot have",
                                   shape->material->name));
    shape->opacity = shape->material->opacity.get();
  }
  shape->camera_visible = sd.camera_visible;
  shape->interior = sd.interior ? d.media.built[*sd.interior] : nullptr;
  shape->exterior = sd.exterior ? d.media.built[*sd.exterior] : nullptr;
}

// A shape and the index of its material.
using Pieces = std::vector<std::pair<std::unique_ptr<Shape>, std::optional<size_t>>>;

// A shape as built, or, for an OBJ mesh with "materials_by_name", one mesh per usemtl name with the scene's
// material of that name (faces before any usemtl: the shape's own "material").
Pieces pieces(ShapeDesc& sd, const SceneDesc& d) {
  Pieces out;
  std::unique_ptr<Shape> shape = sd.shape.take();
  // "power": the emission that spreads it over the whole shape (before a split by material).
  if (sd.emission_is_power && !is_black(sd.emission)) sd.emission = power_to_emission(*shape, sd);
  auto* mesh = dynamic_cast<TriangleMesh*>(shape.get());
  if (!sd.by_name || !mesh) {
    out.emplace_back(std::move(shape), sd.material);
    return out;
  }
  for (auto& [group, piece] : mesh->split_by_group()) {
    const std::string& name = mesh->group_names()[group];
    std::optional<size_t> material = sd.material;
    if (!name.empty()) {
      material.reset();
      for (size_t m = 0; m < d.materials.names.size(); ++m)
        if (d.materials.names[m] == name) material = m;
      if (!material) {
        std::string known;
        for (const std::string& k : d.materials.names) known += (known.empty() ? "'" : ", '") + k + "'";
        throw InputError(sd.file, json_pointer_append(sd.json_path, "file"),
                         fmt::format("usemtl '{}' names no material of the scene (defined: {})", name,
                                     known.empty() ? "none" : known));
      }
    } else if (!material && is_black(sd.emission) && !sd.interior && !sd.exterior) {
      throw InputError(sd.file, sd.json_path, "faces before the file's first usemtl need the shape's \"material\"");
    }
    out.emplace_back(std::move(piece), material);
  }
  return out;
}

// The shapes of each of the scene's objects, stored once for the instances that place them.
void build_objects(SceneDesc& d, Scene& scene) {
  for (size_t o = 0; o < d.objects.size(); ++o) {
    std::vector<std::unique_ptr<Shape>> shapes;
    for (size_t i = 0; i < d.objects[o].shapes.size(); ++i) {
      ShapeDesc& sd = d.objects[o].shapes[i];
      for (auto& [shape, material] : pieces(sd, d)) {
        shape->name = fmt::format("objects.{}[{}]", d.object_names[o], i);
        dress(shape.get(), sd, material, d, scene);
        shapes.push_back(std::move(shape));
      }
    }
    d.objects[o].built = std::make_shared<const InstancedObject>(std::move(shapes));
  }
}

// The lights' power, checked once the scene is built (and each keyed emitter posed at its keys).
void check_lights(Scene& scene, const JsonSource& src, const std::vector<std::string>& light_paths) {
  // Emission times area (or the environment's radiance over the scene's bounds) must stay a finite float with
  // room to spare, or the light would silently turn black or break light selection.
  for (size_t i = 0; i < scene.lights.size(); ++i) {
    const Rgb power = scene.lights[i]->power();
    if (!is_finite(power) || max_component(power) > kMaxLightPower)
      throw InputError(src.display_name, light_paths[i],
                       fmt::format("the light's power ({:.3g}) is beyond kozu's range (at most {:g}); lower its "
                                   "emission or its size",
                                   is_finite(power) ? max_component(power) : kInfinity, kMaxLightPower));
  }
  // A keyed emitter at each of its keys (where a linearly keyed scale is largest, as a rule; every frame is checked
  // again when it is posed), before any frame is rendered.
  for (const Scene::AnimatedShape& a : scene.animated_shapes) {
    if (a.lights.empty()) continue;
    const ShapeTrack& track = scene.animation.shapes[a.track];
    for (size_t k = 0; k < track.keys.size(); ++k) {
      try {
        scene.pose_shapes(track.keys[k].time);
      } catch (const std::invalid_argument& e) {
        throw InputError(src.display_name, json_pointer_append(track.json_path, k), e.what());
      }
    }
  }
}

}  // namespace

// Build: the scene's models, the shapes' area lights, the accelerator.
std::unique_ptr<Scene> build_scene(SceneDesc& d, const JsonSource& src) {
  auto scene = std::make_unique<Scene>();
  scene->textures = std::move(d.textures);
  scene->camera = d.gltf_direct ? gltf_direct_camera(d) : d.camera;
  scene->animation = d.animation;
  for (const SourcePtr& f : d.sources)  // the parse phase's, then the loaders'
    scene->warnings.insert(scene->warnings.end(), f->warnings.begin(), f->warnings.end());
  scene->warnings.insert(scene->warnings.end(), d.warnings.begin(), d.warnings.end());
  scene->settings = d.settings;
  for (size_t i = 0; i < d.materials.models.size(); ++i) {
    scene->materials.push_back(d.materials.models[i].take());
    scene->materials.back()->name = d.materials.names[i];
    d.materials.built.push_back(scene->materials.back().get());
  }
  for (size_t i = 0; i < d.media.models.size(); ++i) {
    scene->media.push_back(d.media.models[i].take());
    scene->media.back()->name = d.media.names[i];
    d.media.built.push_back(scene->media.back().get());
  }
  if (d.camera_medium) scene->camera_medium = d.media.built[*d.camera_medium];
  std::vector<std::string> light_paths;  // the JSON path of each light, for messages
  build_objects(d, *scene);
  // Instances are small, but a scene may place millions of them: their memory is checked before any is created.
  size_t instance_count = 0;
  for (const ShapeDesc& sd : d.shapes) instance_count += sd.object || sd.ellipsoid ? 1 : 0;
  check_instance_memory(instance_count, src.display_name, "/shapes");
  for (size_t i = 0; i < d.shapes.size(); ++i) {
    ShapeDesc& sd = d.shapes[i];
    Pieces built;
    if (sd.object)
      built.emplace_back(std::make_unique<Instance>(d.objects[*sd.object].built, sd.placement), std::nullopt);
    else
      built = pieces(sd, d);
    for (auto& [shape, material] : built) {
      shape->name = fmt::format("shapes[{}]", i);
      if (!sd.object) dress(shape.get(), sd, material, d, *scene);
      if (sd.ellipsoid) {
        std::vector<std::unique_ptr<Shape>> sphere;
        sphere.push_back(std::move(shape));
        shape = std::make_unique<Instance>(std::make_shared<const InstancedObject>(std::move(sphere)), sd.placement);
        shape->name = fmt::format("shapes[{}]", i);
      }
      const size_t first_light = scene->lights.size();
      if (!is_black(sd.emission)) {
        add_area_lights(*shape, sd, *scene);
        light_paths.resize(scene->lights.size(),
                           json_pointer_append(sd.json_path, sd.emission_is_power ? "power" : "emission"));
      }
      if (sd.track) {
        // A keyed emitter's area lights follow its poses (Light::refit).
        std::vector<Light*> lights;
        for (size_t l = first_light; l < scene->lights.size(); ++l) lights.push_back(scene->lights[l].get());
        scene->animated_shapes.push_back({shape.get(), *sd.track, glm::inverse(sd.placement), std::move(lights)});
      }
      scene->shapes.push_back(std::move(shape));
    }
  }
  for (LightDesc& l : d.lights) {
    scene->lights.push_back(l.light.take());
    light_paths.push_back(l.json_path);
  }

  for (const SourcePtr& f : d.sources)
    scene->input_files.insert(scene->input_files.end(), f->files.begin(), f->files.end());
  scene->build();
  scene->set_media_view();
  check_lights(*scene, src, light_paths);
  if (std::none_of(scene->lights.begin(), scene->lights.end(),
                   [](const auto& l) { return max_component(l->power()) > 0.0f; }))
    scene->warnings.push_back(
        fmt::format("{}: the scene has no light{}, so the image is black: add a light, an emissive shape or an "
                    "environment",
                    src.display_name, scene->lights.empty() ? "" : " that emits"));
  return scene;
}

}  // namespace kozu::scene_load
