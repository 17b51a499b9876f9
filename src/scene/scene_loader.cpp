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

  explicit Named(const char* kind_name) : kind(kind_name) {}
  // Reads root[key] (an object of name: description), parsing each description with parse.
  template <class Parse>
  void parse(const JsonObject& root, std::string_view key, Parse&& parse_one) {
    if (!root.has(key)) return;
    const JsonObject all = root.get_object(key);
    for (const std::string& name : all.keys()) {
      models.push_back(parse_one(all.get_object(name)));
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

// The whole scene after the parse phase.
struct SceneDesc {
  std::unique_ptr<TextureCache> textures;
  Camera camera;
  RenderSettings settings;
  Named<Material> materials{"material"};
  Named<Medium> media{"medium"};
  std::optional<size_t> camera_medium;
  std::vector<ShapeDesc> shapes;
  std::vector<LightDesc> lights;
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

// Parse: every key is read and checked and every name resolved before any file is opened.
SceneDesc parse_scene(const JsonObject& root, const SceneLoadOptions& options) {
  SceneDesc d;
  // Made when the first image texture is parsed: most scenes have none.
  const auto textures = [&d, &options]() {
    if (!d.textures) d.textures = std::make_unique<TextureCache>(options.textures);
    return d.textures.get();
  };
  std::string camera_medium;
  d.camera = parse_camera(root.get_object("camera"), &camera_medium);
  if (root.has("render")) d.settings = parse_render_settings(root.get_object("render"));
  const MaterialParseContext material_ctx{textures};
  d.materials.parse(root, "materials", [&](const JsonObject& m) { return parse_material(m, material_ctx); });
  d.media.parse(root, "media", &parse_medium);
  if (!camera_medium.empty()) d.camera_medium = d.media.index(camera_medium, root.source(), "/camera/medium");
  const JsonArray shapes = root.get_array("shapes");
  for (size_t i = 0; i < shapes.size(); ++i)
    d.shapes.push_back(parse_shape_desc(shapes.object(i), d.materials, d.media));
  if (root.has("lights")) {
    const JsonArray lights = root.get_array("lights");
    bool have_env = false;
    for (size_t i = 0; i < lights.size(); ++i) {
      std::string type;
      d.lights.push_back({lights.path_of(i), parse_light(lights.object(i), &type)});
      if (type == "environment" && have_env) lights.fail(i, "only one environment light is allowed");
      have_env |= type == "environment";
    }
  }
  root.ignore("comment");
  root.finish({"camera", "render", "materials", "media", "shapes", "lights"});
  return d;
}

// Load: the files every model needs, all at once.
void load_files(SceneDesc& d) {
  std::vector<std::function<void()>> jobs;
  for (Deferred<Material>& m : d.materials.models) add_load_job(m, jobs);
  for (Deferred<Medium>& m : d.media.models) add_load_job(m, jobs);
  for (ShapeDesc& s : d.shapes) add_load_job(s.shape, jobs);
  for (LightDesc& l : d.lights) add_load_job(l.light, jobs);
  load_all(jobs);
}

// Build: the scene's models, the shapes' area lights, the accelerator.
std::unique_ptr<Scene> build_scene(SceneDesc& d, const JsonSource& src) {
  auto scene = std::make_unique<Scene>();
  scene->textures = std::move(d.textures);
  scene->camera = d.camera;
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
  for (size_t i = 0; i < d.shapes.size(); ++i) {
    ShapeDesc& sd = d.shapes[i];
    std::unique_ptr<Shape> shape = sd.shape.take();
    shape->name = fmt::format("shapes[{}]", i);
    shape->material = sd.material ? d.materials.built[*sd.material] : nullptr;
    if (shape->material && shape->material->perturbs_shading()) shape->prepare_tangents();
    if (shape->material && shape->material->opacity) {
      // Area lights sample points on the whole surface: holes would still emit.
      if (!is_black(sd.emission))
        throw InputError(src.display_name, json_pointer_append(sd.json_path, "material"),
                         fmt::format("material '{}' has an opacity cut-out, which an emitting shape cannot have",
                                     shape->material->name));
      shape->opacity = shape->material->opacity.get();
    }
    shape->interior = sd.interior ? d.media.built[*sd.interior] : nullptr;
    shape->exterior = sd.exterior ? d.media.built[*sd.exterior] : nullptr;
    if (!is_black(sd.emission)) {
      add_area_lights(*shape, sd, *scene);
      light_paths.resize(scene->lights.size(), json_pointer_append(sd.json_path, "emission"));
    }
    scene->shapes.push_back(std::move(shape));
  }
  for (LightDesc& l : d.lights) {
    scene->lights.push_back(l.light.take());
    light_paths.push_back(l.json_path);
  }

  scene->input_files = src.files;
  scene->build();
  scene->set_media_view();
  // Emission times area (or the environment's radiance over the scene's bounds) must stay a finite float with
  // room to spare, or the light would silently turn black or break light selection.
  for (size_t i = 0; i < scene->lights.size(); ++i) {
    const Rgb power = scene->lights[i]->power();
    if (!is_finite(power) || max_component(power) > kMaxLightPower)
      throw InputError(src.display_name, light_paths[i],
                       fmt::format("the light's power ({:.3g}) is beyond kozu's range (at most {:g}); lower its "
                                   "emission or its size",
                                   is_finite(power) ? max_component(power) : kInfinity, kMaxLightPower));
  }
  return scene;
}

std::unique_ptr<Scene> load_from_json(const Json& root_json, const SourcePtr& src, const SceneLoadOptions& options) {
  SceneDesc desc = parse_scene(JsonObject(root_json, "", src), options);
  load_files(desc);
  return build_scene(desc, *src);
}

}  // namespace

std::unique_ptr<Scene> load_scene_text(std::string_view json, const std::string& display_name,
                                       const std::filesystem::path& base_dir, const SceneLoadOptions& options) {
  auto src = std::make_shared<JsonSource>(JsonSource{display_name, base_dir});
  const Json root = parse_json_text(json, display_name);
  return load_from_json(root, src, options);
}

std::unique_ptr<Scene> load_scene_file(const std::filesystem::path& file, const SceneLoadOptions& options) {
  const std::string text = read_input_file(file);
  std::filesystem::path base = file.parent_path();
  if (base.empty()) base = ".";
  auto scene = load_scene_text(text, file.string(), base, options);
  scene->input_files.insert(scene->input_files.begin(), file);
  return scene;
}

std::string_view demo_scene_json() { return kDemoSceneJson; }

std::unique_ptr<Scene> load_demo_scene(const SceneLoadOptions& options) {
  return load_scene_text(kDemoSceneJson, "<demo>", std::filesystem::current_path(), options);
}

}  // namespace kozu
