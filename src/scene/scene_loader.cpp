#include "scene/scene_loader.h"

#include "core/error.h"
#include "core/file_io.h"
#include "core/input_bounds.h"
#include "core/json_reader.h"
#include "geometry/shape_registry.h"
#include "lights/area.h"
#include "materials/material.h"
#include "media/medium.h"
#include "scene/render_settings.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <exception>
#include <functional>
#include <optional>

namespace kozu {

extern const std::string_view kDemoSceneJson;

namespace {

using SourcePtr = std::shared_ptr<const JsonSource>;

// ---------------------------------------------------------------------------------------------
// Descriptions produced by the parse phase.

// The named models of one kind ("materials", "media"), in the file's order, with their names resolved here.
template <class T>
struct Named {
  const char* kind;  // "material", "medium": for messages
  std::vector<std::string> names;
  std::vector<Deferred<T>> models;
  std::vector<const T*> built;  // filled by the build phase

  // Reads root[key] (an object of name: description), parsing each description with parse.
  Named(const char* kind_name, const JsonObject& root, std::string_view key, Deferred<T> (*parse)(const JsonObject&))
      : kind(kind_name) {
    if (!root.has(key)) return;
    const JsonObject all = root.get_object(key);
    for (const std::string& name : all.keys()) {
      models.push_back(parse(all.get_object(name)));
      names.push_back(name);
    }
  }
  // The index of name; an unknown name fails at json_path, listing the names defined.
  size_t index(const std::string& name, const JsonSource& src, const std::string& json_path) const {
    for (size_t i = 0; i < names.size(); ++i)
      if (names[i] == name) return i;
    std::string known;
    for (const std::string& k : names) known += (known.empty() ? "'" : ", '") + k + "'";
    throw InputError(src.display_name, json_path,
                     fmt::format("unknown {} '{}' (defined: {})", kind, name, known.empty() ? "none" : known));
  }
};

struct ShapeDesc {
  std::string type;  // sphere | quad | polygon | mesh
  std::string json_path;
  std::optional<size_t> material, interior, exterior;  // indices into the named lists
  Rgb emission{0.0f};
  bool two_sided = false;
  Deferred<Shape> shape;
};

struct LightDesc {
  std::string json_path;
  Deferred<Light> light;
};

// ---------------------------------------------------------------------------------------------
// Parse phase.

Camera parse_camera(const JsonObject& c, std::string* medium) {
  const std::string type = c.get_enum("type", {"perspective", "thinlens"}, std::string("perspective"));
  const Vec3 position = get_point(c, "position");
  const Vec3 look_at = get_point(c, "look_at");
  const Vec3 up = c.get_direction("up", Vec3(0, 1, 0));
  if (!(glm::length(look_at - position) > 0.0f)) c.fail("look_at", "look_at must differ from position");
  const Vec3 fwd = glm::normalize(look_at - position);
  if (glm::length(glm::cross(fwd, glm::normalize(up))) < 1e-4f) c.fail("up", "up is parallel to the view direction");
  const float fov = c.get_float("fov", 40.0f, Range{0.0, 180.0, true, true});
  const Vec2i res = c.has("resolution") ? parse_resolution(c) : Vec2i(1280, 720);
  float aperture = 0.0f, focus = glm::length(look_at - position);
  if (type == "thinlens") {
    aperture = c.get_float("aperture_radius", {}, kSizeRange);
    focus = c.get_float("focus_distance", focus, kSizeRange);
  } else {
    for (const char* key : {"aperture_radius", "focus_distance"})
      if (c.has(key)) c.fail(key, fmt::format("'{}' needs a thin-lens camera: add \"type\": \"thinlens\"", key));
  }
  if (c.has("medium")) *medium = c.get_string("medium");
  c.finish({"aperture_radius", "focus_distance", "resolution", "medium"});
  return Camera(position, look_at, up, fov, res, aperture, focus);
}

// A shape's shared keys (material, emission, media), then its geometry (geometry/shape_registry.h).
ShapeDesc parse_shape_desc(const JsonObject& s, const Named<Material>& materials, const Named<Medium>& media) {
  ShapeDesc d;
  d.json_path = s.path();
  const JsonSource& src = s.source();
  if (s.has("emission")) d.emission = s.get_rgb("emission", {}, Range::non_negative());
  if (s.has("two_sided")) d.two_sided = s.get_bool("two_sided");
  if (s.has("interior")) d.interior = media.index(s.get_string("interior"), src, s.path_of("interior"));
  if (s.has("exterior")) d.exterior = media.index(s.get_string("exterior"), src, s.path_of("exterior"));
  if (s.has("material")) {
    const std::string name = s.get_string("material");
    if (name.empty()) s.fail("material", "expected a material name");
    d.material = materials.index(name, src, s.path_of("material"));
  } else if (is_black(d.emission) && !d.interior && !d.exterior) {
    s.fail("missing required key 'material' (only emitters and medium boundaries may omit it)");
  }
  s.ignore("name");
  d.shape = parse_shape(s, &d.type);
  return d;
}

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
    scene.lights.push_back(std::make_unique<PolygonLight>(mesh, d.emission, d.two_sided));
    shape.lights.push_back(scene.lights.back().get());
    return;
  }
  for (uint32_t p = 0; p < mesh->primitive_count(); ++p) {
    scene.lights.push_back(std::make_unique<TriangleLight>(mesh, p, d.emission, d.two_sided));
    shape.lights.push_back(scene.lights.back().get());
  }
}

// Runs every load job (files of media, meshes, environment images) in parallel; the first error in the file's
// order is thrown.
void load_all(const std::vector<std::function<void()>>& jobs) {
  std::vector<std::exception_ptr> errors(jobs.size());
  tbb::parallel_for(size_t{0}, jobs.size(), [&](size_t i) {
    try {
      jobs[i]();
    } catch (...) {
      errors[i] = std::current_exception();
    }
  });
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
}

template <class T>
void add_load_job(Deferred<T>& d, std::vector<std::function<void()>>& jobs) {
  if (d.needs_load()) jobs.emplace_back([&d] { d.load(); });
}

// ---------------------------------------------------------------------------------------------
// The three phases.

std::unique_ptr<Scene> load_from_json(const Json& root_json, const SourcePtr& src) {
  const JsonObject root(root_json, "", src);
  auto scene = std::make_unique<Scene>();

  // Parse: every key is read and checked and every name resolved before any file is opened.
  std::string camera_medium_name;
  scene->camera = parse_camera(root.get_object("camera"), &camera_medium_name);
  if (root.has("render")) scene->settings = parse_render_settings(root.get_object("render"));
  Named<Material> materials("material", root, "materials", &parse_material);
  Named<Medium> media("medium", root, "media", &parse_medium);
  std::optional<size_t> camera_medium;
  if (!camera_medium_name.empty()) camera_medium = media.index(camera_medium_name, *src, "/camera/medium");
  const JsonArray shapes = root.get_array("shapes");
  std::vector<ShapeDesc> shape_descs;
  for (size_t i = 0; i < shapes.size(); ++i) shape_descs.push_back(parse_shape_desc(shapes.object(i), materials, media));
  std::vector<LightDesc> light_descs;
  if (root.has("lights")) {
    const JsonArray lights = root.get_array("lights");
    bool have_env = false;
    for (size_t i = 0; i < lights.size(); ++i) {
      std::string type;
      light_descs.push_back({lights.path_of(i), parse_light(lights.object(i), &type)});
      if (type == "environment" && have_env) lights.fail(i, "only one environment light is allowed");
      have_env |= type == "environment";
    }
  }
  root.ignore("comment");
  root.finish({"camera", "render", "materials", "media", "shapes", "lights"});

  // Load: the files every model needs, all at once.
  std::vector<std::function<void()>> jobs;
  for (Deferred<Material>& m : materials.models) add_load_job(m, jobs);
  for (Deferred<Medium>& m : media.models) add_load_job(m, jobs);
  for (ShapeDesc& d : shape_descs) add_load_job(d.shape, jobs);
  for (LightDesc& d : light_descs) add_load_job(d.light, jobs);
  load_all(jobs);

  // Build: the scene's models, the shapes' area lights, the accelerator.
  for (size_t i = 0; i < materials.models.size(); ++i) {
    scene->materials.push_back(materials.models[i].take());
    scene->materials.back()->name = materials.names[i];
    materials.built.push_back(scene->materials.back().get());
  }
  for (size_t i = 0; i < media.models.size(); ++i) {
    scene->media.push_back(media.models[i].take());
    scene->media.back()->name = media.names[i];
    media.built.push_back(scene->media.back().get());
  }
  if (camera_medium) scene->camera_medium = media.built[*camera_medium];
  std::vector<std::string> light_paths;  // the JSON path of each light, for messages
  for (size_t i = 0; i < shape_descs.size(); ++i) {
    ShapeDesc& d = shape_descs[i];
    std::unique_ptr<Shape> shape = d.shape.take();
    shape->name = fmt::format("shapes[{}]", i);
    shape->material = d.material ? materials.built[*d.material] : nullptr;
    shape->interior = d.interior ? media.built[*d.interior] : nullptr;
    shape->exterior = d.exterior ? media.built[*d.exterior] : nullptr;
    if (!is_black(d.emission)) {
      add_area_lights(*shape, d, *scene);
      light_paths.resize(scene->lights.size(), json_pointer_append(d.json_path, "emission"));
    }
    scene->shapes.push_back(std::move(shape));
  }
  for (LightDesc& d : light_descs) {
    scene->lights.push_back(d.light.take());
    light_paths.push_back(d.json_path);
  }

  scene->input_files = src->files;
  scene->build();
  scene->set_media_view();
  // Emission times area (or the environment's radiance over the scene's bounds) must stay a finite float with
  // room to spare, or the light would silently turn black or break light selection.
  for (size_t i = 0; i < scene->lights.size(); ++i) {
    const Rgb power = scene->lights[i]->power();
    if (!is_finite(power) || max_component(power) > kMaxLightPower)
      throw InputError(src->display_name, light_paths[i],
                       fmt::format("the light's power ({:.3g}) is beyond kozu's range (at most {:g}); lower its "
                                   "emission or its size",
                                   is_finite(power) ? max_component(power) : kInfinity, kMaxLightPower));
  }
  return scene;
}

}  // namespace

std::unique_ptr<Scene> load_scene_text(std::string_view json, const std::string& display_name,
                                       const std::filesystem::path& base_dir) {
  auto src = std::make_shared<JsonSource>(JsonSource{display_name, base_dir});
  const Json root = parse_json_text(json, display_name);
  return load_from_json(root, src);
}

std::unique_ptr<Scene> load_scene_file(const std::filesystem::path& file) {
  const std::string text = read_input_file(file);
  std::filesystem::path base = file.parent_path();
  if (base.empty()) base = ".";
  auto scene = load_scene_text(text, file.string(), base);
  scene->input_files.insert(scene->input_files.begin(), file);
  return scene;
}

std::string_view demo_scene_json() { return kDemoSceneJson; }

std::unique_ptr<Scene> load_demo_scene() {
  return load_scene_text(kDemoSceneJson, "<demo>", std::filesystem::current_path());
}

}  // namespace kozu
