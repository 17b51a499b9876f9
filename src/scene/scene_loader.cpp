#include "scene/scene_loader.h"

#include "core/error.h"
#include "core/file_io.h"
#include "core/input_bounds.h"
#include "core/json_reader.h"
#include "geometry/mesh_cleanup.h"
#include "geometry/shape_registry.h"
#include "io/gltf_reader.h"
#include "lights/area.h"
#include "materials/material.h"
#include "media/medium.h"
#include "scene/render_settings.h"
#include "textures/texture_parse.h"

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

// A "gltf" shape: the file, read by the load job, becomes shapes, materials, media and lights before the build.
struct GltfDesc {
  std::filesystem::path file;
  GltfImportOptions options;
  GltfScene scene;  // filled by the load job
  std::string scene_name;  // the scene file, for messages
};

struct ShapeDesc {
  std::string type;  // sphere | quad | polygon | mesh | gltf
  std::string json_path;
  std::optional<size_t> material, interior, exterior;  // indices into the named lists
  Rgb emission{0.0f};
  std::shared_ptr<Deferred<Texture>> emission_texture;  // "emission": {texture} (quads and polygons); emission is 1
  bool two_sided = false;
  // "power" (W) instead of "emission": emission then holds the power until the shape's area is known (build_scene).
  bool emission_is_power = false;
  Deferred<Shape> shape;
  std::shared_ptr<GltfDesc> gltf;  // type "gltf" only (shape then stays empty)
  std::string name;                // "name" (optional)
  Mat4 placement{1.0f};            // the shape's own "transform"
  std::optional<size_t> track;     // its track in animation.shapes, when one moves it
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
  Animation animation;
  Named<Material> materials{"material"};
  Named<Medium> media{"medium"};
  std::optional<size_t> camera_medium;
  std::vector<ShapeDesc> shapes;
  std::vector<LightDesc> lights;
  MaterialParseContext material_ctx;
  std::vector<std::string> warnings;
  // A glTF file rendered directly (load_gltf_file): its camera, its lights, the bounds of its meshes.
  bool gltf_direct = false;
  std::optional<GltfCamera> gltf_camera;
  size_t gltf_lights = 0;
  Vec3 lo{kInfinity}, hi{-kInfinity};
};

// ---------------------------------------------------------------------------------------------
// Parse phase.

Camera parse_camera(const JsonObject& c, std::string* medium) {
  const std::string type =
      c.get_enum("type", {"perspective", "thinlens", "orthographic", "panorama"}, std::string("perspective"));
  const Vec3 position = get_point(c, "position");
  const Vec3 look_at = get_point(c, "look_at");
  const Vec3 up = c.get_direction("up", Vec3(0, 1, 0));
  if (!(glm::length(look_at - position) > 0.0f)) c.fail("look_at", "look_at must differ from position");
  const Vec3 fwd = glm::normalize(look_at - position);
  if (glm::length(glm::cross(fwd, glm::normalize(up))) < 1e-4f) c.fail("up", "up is parallel to the view direction");
  const Vec2i res = c.has("resolution") ? parse_resolution(c) : Vec2i(1280, 720);
  if (type == "orthographic" || type == "panorama") {
    for (const char* key : {"fov", "aperture_radius", "focus_distance"})
      if (c.has(key))
        c.fail(key, fmt::format("'{}' does not apply to {} camera", key,
                                type == "panorama" ? "a panorama" : "an orthographic"));
    float scale = 1.0f;
    if (type == "orthographic") scale = c.get_float("scale", {}, kSizeRange);
    if (c.has("medium")) *medium = c.get_string("medium");
    c.finish({"resolution", "medium", "scale"});
    return Camera::with_projection(type == "panorama" ? Camera::Projection::Panorama : Camera::Projection::Orthographic,
                                   position, look_at, up, res, scale);
  }
  if (c.has("scale"))
    c.fail("scale", "'scale' is the height of an orthographic camera: add \"type\": \"orthographic\"");
  const float fov = c.get_float("fov", 40.0f, Range{0.0, 180.0, true, true});
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
// A "gltf" shape (docs/scene-format.md): the file, its placement and its light units; materials, emission and
// media come from the file.
ShapeDesc parse_gltf_desc(const JsonObject& s, const SceneLoadOptions& options) {
  ShapeDesc d;
  d.type = "gltf";
  d.json_path = s.path();
  d.gltf = std::make_shared<GltfDesc>();
  d.gltf->file = s.get_path("file");
  d.gltf->scene_name = s.source().display_name;
  const std::string ext = lower_extension(d.gltf->file);
  if (ext != ".gltf" && ext != ".glb") s.fail("file", "expected a .gltf or .glb file");
  if (s.has("transform")) d.gltf->options.root = read_transform(s.get_object("transform")).matrix();
  d.placement = d.gltf->options.root;
  // glTF gives candela and lux; kozu's lights take W/sr and W/m² (683 lm/W, the luminous efficacy that defines
  // the candela), or the numbers as they are.
  const std::string units = s.get_enum("light_units", {"photometric", "radiometric"}, std::string("photometric"));
  d.gltf->options.light_scale = units == "photometric" ? 1.0 / 683.0 : 1.0;
  const std::filesystem::path& tx = options.textures.convert_dir;
  d.gltf->options.image_dir = tx.empty() ? std::filesystem::temp_directory_path() / "kozu-gltf" : tx / "gltf";
  for (const char* key : {"material", "emission", "power", "two_sided", "interior", "exterior"})
    if (s.has(key)) s.fail(key, fmt::format("a gltf shape takes its materials from the file: remove '{}'", key));
  if (s.has("name")) d.name = s.get_string("name");
  s.get_enum("type", {"gltf"});
  s.finish();
  return d;
}

ShapeDesc parse_shape_desc(const JsonObject& s, const Named<Material>& materials, const Named<Medium>& media,
                           const SceneLoadOptions& options, const std::function<TextureCache*()>& textures) {
  if (s.has("type") && s.raw("type") == "gltf") return parse_gltf_desc(s, options);
  ShapeDesc d;
  d.json_path = s.path();
  const JsonSource& src = s.source();
  if (s.has("emission") && s.has("power"))
    s.fail("power", "give either 'emission' or 'power' (watts), not both");
  if (s.has("power")) {
    d.emission = s.get_rgb("power", {}, Range::closed(0.0, double(kMaxLightPower)));
    d.emission_is_power = true;
  } else if (s.has("emission") && s.raw("emission").is_object()) {
    // A textured emitter (docs/lights.md): only a quad or polygon light has the (u, v) square it is sampled and
    // prefiltered over.
    const std::string type = s.has("type") ? s.get_string("type") : std::string();
    if (type != "quad" && type != "polygon")
      s.fail("emission", fmt::format("a textured emission needs a quad or polygon shape, not a {}",
                                     type.empty() ? std::string("shape without a type") : type));
    d.emission_texture = std::make_shared<Deferred<Texture>>(
        parse_texture(s, "emission", {TextureUse::Color, textures, Range::non_negative()}));
    d.emission = Rgb(1.0f);
  } else if (s.has("emission")) {
    d.emission = s.get_rgb("emission", {}, Range::non_negative());
  }
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
  if (s.has("name")) d.name = s.get_string("name");
  d.shape = parse_shape(s, &d.type);
  if (d.type != "sphere" && s.has("transform")) d.placement = read_transform(s.get_object("transform")).matrix();
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
Rgb power_to_emission(const Shape& shape, const ShapeDesc& sd, const JsonSource& src) {
  double area = 0.0;
  for (uint32_t p = 0; p < shape.primitive_count(); ++p) area += double(shape.primitive_area(p));
  const double per_unit = M_PI * area * (sd.two_sided ? 2.0 : 1.0);
  const std::string path = json_pointer_append(sd.json_path, "power");
  const double radiance = double(max_component(sd.emission)) / per_unit;
  if (!(per_unit > 0.0))
    throw InputError(src.display_name, path, "the shape has no area, so it cannot emit a power: give 'emission'");
  if (!(radiance <= kMaxRadiance))
    throw InputError(src.display_name, path,
                     fmt::format("{:g} W over an area of {:.3g} is a radiance of {:.3g}, beyond kozu's range (at most "
                                 "{:g})",
                                 double(max_component(sd.emission)), area, radiance, kMaxRadiance));
  return Rgb(Vec3d(sd.emission) / per_unit);
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

// Each shape track of the animation to the one shape of its name, which must be able to move: not an emitter
// (its area lights are built once), not mirrored by its own transform, a sphere only under uniform scales.
void resolve_shape_tracks(SceneDesc& d, const JsonSource& src) {
  for (size_t t = 0; t < d.animation.shapes.size(); ++t) {
    const ShapeTrack& track = d.animation.shapes[t];
    const auto fail = [&](const std::string& message) { throw InputError(src.display_name, track.json_path, message); };
    std::vector<size_t> named;
    std::string names;
    for (size_t i = 0; i < d.shapes.size(); ++i) {
      if (d.shapes[i].name == track.name) named.push_back(i);
      if (!d.shapes[i].name.empty()) names += (names.empty() ? "" : ", ") + d.shapes[i].name;
    }
    if (named.empty())
      fail(fmt::format("no shape is named '{}' (named shapes: {}); give the shape a \"name\"", track.name,
                       names.empty() ? "none" : names));
    if (named.size() > 1)
      fail(fmt::format("{} shapes are named '{}' ({} and {}): an animated shape's name must be unique", named.size(),
                       track.name, d.shapes[named[0]].json_path, d.shapes[named[1]].json_path));
    ShapeDesc& sd = d.shapes[named[0]];
    if (!is_black(sd.emission) || sd.emission_texture)
      fail(fmt::format("shape '{}' ({}) emits light: emitters cannot be animated yet (their lights are built once)",
                       track.name, sd.json_path));
    if (glm::determinant(Mat3(sd.placement)) < 0.0f)
      fail(fmt::format("shape '{}' ({}) is mirrored by its own transform: an animated shape cannot be", track.name,
                       sd.json_path));
    if (sd.type == "sphere" && !track.uniform_scale())
      fail(fmt::format("shape '{}' is a sphere: its keys must scale x, y and z alike", track.name));
    sd.track = t;
  }
}

// ---------------------------------------------------------------------------------------------
// The three phases.

// Parse: every key is read and checked and every name resolved before any file is opened.
SceneDesc parse_scene(const JsonObject& root, const SceneLoadOptions& options, bool gltf_direct = false) {
  SceneDesc d;
  d.gltf_direct = gltf_direct;
  // Made when the first image texture is parsed: most scenes have none.
  const auto textures = [&d, &options]() {
    if (!d.textures) d.textures = std::make_unique<TextureCache>(options.textures);
    return d.textures.get();
  };
  std::string camera_medium;
  // A glTF file rendered directly gets its camera after loading (build_scene).
  if (!gltf_direct) d.camera = parse_camera(root.get_object("camera"), &camera_medium);
  if (root.has("render")) d.settings = parse_render_settings(root.get_object("render"));
  if (root.has("animation")) {
    if (gltf_direct) root.fail("animation", "a glTF file rendered directly has no animation block");
    d.animation = parse_animation(root.get_object("animation"), camera_key(d.camera));
  }
  d.material_ctx = MaterialParseContext{textures};
  d.materials.parse(root, "materials", [&](const JsonObject& m) { return parse_material(m, d.material_ctx); });
  d.media.parse(root, "media", &parse_medium);
  if (!camera_medium.empty()) d.camera_medium = d.media.index(camera_medium, root.source(), "/camera/medium");
  const JsonArray shapes = root.get_array("shapes");
  for (size_t i = 0; i < shapes.size(); ++i)
    d.shapes.push_back(parse_shape_desc(shapes.object(i), d.materials, d.media, options, textures));
  resolve_shape_tracks(d, root.source());
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
  root.finish({"camera", "render", "animation", "materials", "media", "shapes", "lights"});
  return d;
}

// Load: the files every model needs, all at once.
void load_files(SceneDesc& d) {
  std::vector<std::function<void()>> jobs;
  for (Deferred<Material>& m : d.materials.models) add_load_job(m, jobs);
  for (Deferred<Medium>& m : d.media.models) add_load_job(m, jobs);
  for (ShapeDesc& s : d.shapes) {
    add_load_job(s.shape, jobs);
    if (s.emission_texture) add_load_job(*s.emission_texture, jobs);
    if (s.gltf) {
      jobs.emplace_back([&s, direct = d.gltf_direct] {
        try {
          s.gltf->scene = read_gltf(s.gltf->file, s.gltf->options);
        } catch (const InputError& e) {
          if (direct) throw;  // the file is the scene: its own message says it all
          throw InputError(s.gltf->scene_name, json_pointer_append(s.json_path, "file"), e.what());
        } catch (const std::bad_alloc&) {
          throw;
        } catch (const std::exception& e) {
          throw InputError(s.gltf->file.string(), "", e.what());
        }
      });
    }
  }
  for (LightDesc& l : d.lights) add_load_job(l.light, jobs);
  load_all(jobs);
}

// The shapes, materials, media and lights of each glTF file (after load_files): parsed as kozu descriptions whose
// messages name the glTF file, and their textures prepared in parallel.
void expand_gltf(SceneDesc& d) {
  std::vector<ShapeDesc> shapes;
  std::vector<std::function<void()>> jobs;
  const size_t first_material = d.materials.models.size(), first_light = d.lights.size();
  for (ShapeDesc& sd : d.shapes) {
    if (!sd.gltf) {
      shapes.push_back(std::move(sd));
      continue;
    }
    GltfScene& g = sd.gltf->scene;
    const std::filesystem::path& file = sd.gltf->file;
    auto src = std::make_shared<JsonSource>(JsonSource{file.string(), file.parent_path()});
    for (const std::string& w : g.warnings) d.warnings.push_back(w);
    const size_t material_base = d.materials.models.size();
    for (size_t i = 0; i < g.materials.size(); ++i) {
      Json& m = g.materials[i];
      d.materials.models.push_back(
          parse_material(JsonObject(m, fmt::format("/materials/{}", i), src), d.material_ctx));
      d.materials.names.push_back(file.filename().string() + ":" + g.material_names[i]);
    }
    std::vector<std::optional<size_t>> interior(g.media.size());
    for (size_t i = 0; i < g.media.size(); ++i) {
      if (g.media[i].is_null()) continue;
      interior[i] = d.media.models.size();
      d.media.models.push_back(
          parse_medium(JsonObject(g.media[i], fmt::format("/materials/{}/extensions/KHR_materials_volume", i), src)));
      d.media.names.push_back(file.filename().string() + ":" + g.material_names[i]);
    }
    for (GltfPrimitive& p : g.primitives) {
      MeshData& mesh = p.mesh;
      for (const Vec3& v : mesh.positions)
        if (!is_finite(v) || !within_bounds(v))
          throw InputError(file.string(), p.json_path, bounds_message(v) + " after the node transforms");
      // Zero-area triangles are common in exported assets and invisible: dropped.
      remove_degenerate_triangles(mesh);
      if (mesh.indices.empty()) continue;
      for (const Vec3& v : mesh.positions) {
        d.lo = glm::min(d.lo, v);
        d.hi = glm::max(d.hi, v);
      }
      ShapeDesc s;
      s.type = "mesh";
      s.json_path = sd.json_path + p.json_path;
      s.material = material_base + size_t(p.material);
      s.emission = g.emission[size_t(p.material)];
      s.two_sided = g.double_sided[size_t(p.material)];
      s.interior = interior[size_t(p.material)];
      s.name = sd.name;
      s.placement = sd.placement;
      s.track = sd.track;
      s.shape = std::make_unique<TriangleMesh>(std::move(mesh.positions), std::move(mesh.indices),
                                               std::move(mesh.normals), std::move(mesh.uvs), std::move(mesh.tangents));
      shapes.push_back(std::move(s));
    }
    for (size_t i = 0; i < g.lights.size(); ++i) {
      d.lights.push_back({fmt::format("{}: /lights/{}", file.string(), i),
                          parse_light(JsonObject(g.lights[i], fmt::format("/lights/{}", i), src))});
      ++d.gltf_lights;
    }
    if (g.camera && !d.gltf_camera) d.gltf_camera = g.camera;
  }
  d.shapes = std::move(shapes);
  for (size_t i = first_material; i < d.materials.models.size(); ++i) add_load_job(d.materials.models[i], jobs);
  for (size_t i = first_light; i < d.lights.size(); ++i) add_load_job(d.lights[i].light, jobs);
  load_all(jobs);
}

// The camera of a glTF file rendered directly: the file's first perspective camera, or one that frames the
// meshes' bounds from a three-quarter view (35° round from +z towards +x, 25° up), the bounding sphere filling
// the vertical field of view.
Camera gltf_direct_camera(const SceneDesc& d) {
  const Vec2i res(1280, 720);
  if (d.gltf_camera) {
    const GltfCamera& c = *d.gltf_camera;
    Vec2i r = res;
    if (c.aspect > 0.0f) r.x = std::clamp(static_cast<int>(std::lround(720.0f * c.aspect)), 1, 65536);
    return Camera(c.position, c.position + c.forward, c.up, c.yfov_degrees, r);
  }
  Vec3 center(0.0f);
  float radius = 1.0f;
  if (d.lo.x <= d.hi.x) {
    center = 0.5f * (d.lo + d.hi);
    radius = std::max(0.5f * glm::length(d.hi - d.lo), 1e-6f);
  }
  const float fov = 40.0f, azimuth = glm::radians(35.0f), elevation = glm::radians(25.0f);
  const Vec3 dir(std::cos(elevation) * std::sin(azimuth), std::sin(elevation), std::cos(elevation) * std::cos(azimuth));
  const float distance = radius / std::sin(glm::radians(fov / 2.0f));
  return Camera(center + distance * dir, center, Vec3(0, 1, 0), fov, res);
}

// Build: the scene's models, the shapes' area lights, the accelerator.
std::unique_ptr<Scene> build_scene(SceneDesc& d, const JsonSource& src) {
  auto scene = std::make_unique<Scene>();
  scene->textures = std::move(d.textures);
  scene->camera = d.gltf_direct ? gltf_direct_camera(d) : d.camera;
  scene->animation = d.animation;
  scene->warnings = src.warnings;  // the parse phase's, then the loaders'
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
  for (size_t i = 0; i < d.shapes.size(); ++i) {
    ShapeDesc& sd = d.shapes[i];
    std::unique_ptr<Shape> shape = sd.shape.take();
    shape->name = fmt::format("shapes[{}]", i);
    shape->material = sd.material ? d.materials.built[*sd.material] : nullptr;
    // An open boundary lets paths into a medium or a subsurface material that never find the way out (or out of
    // one they never entered): not an error (a ground plane may rightly bound an atmosphere), but said.
    const bool subsurface = shape->material && shape->material->has_subsurface();
    if (sd.interior || sd.exterior || subsurface)
      if (const size_t open = shape->open_edges(); open > 0)
        scene->warnings.push_back(InputError::format(
            src.display_name, sd.json_path,
            fmt::format("the shape {} but is not closed ({} edge{} on one triangle only): paths can cross it "
                        "once and end up inside without a way out; close the mesh",
                        subsurface ? "has a subsurface material" : "bounds a medium", open, open == 1 ? "" : "s")));
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
    if (sd.track) {
      if (!is_black(sd.emission))
        throw InputError(
            src.display_name, scene->animation.shapes[*sd.track].json_path,
            fmt::format("{} emits light: emitters cannot be animated yet (their lights are built once)", sd.json_path));
      scene->animated_shapes.push_back({shape.get(), *sd.track, glm::inverse(sd.placement)});
    }
    if (!is_black(sd.emission)) {
      if (sd.emission_is_power) sd.emission = power_to_emission(*shape, sd, src);
      add_area_lights(*shape, sd, *scene);
      light_paths.resize(scene->lights.size(), json_pointer_append(sd.json_path, sd.emission_is_power ? "power" : "emission"));
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
  if (std::none_of(scene->lights.begin(), scene->lights.end(),
                   [](const auto& l) { return max_component(l->power()) > 0.0f; }))
    scene->warnings.push_back(
        fmt::format("{}: the scene has no light{}, so the image is black: add a light, an emissive shape or an "
                    "environment",
                    src.display_name, scene->lights.empty() ? "" : " that emits"));
  return scene;
}

std::unique_ptr<Scene> load_from_json(const Json& root_json, const SourcePtr& src, const SceneLoadOptions& options) {
  SceneDesc desc = parse_scene(JsonObject(root_json, "", src), options);
  load_files(desc);
  expand_gltf(desc);
  return build_scene(desc, *src);
}

}  // namespace

std::unique_ptr<Scene> load_scene_text(std::string_view json, const std::string& display_name,
                                       const std::filesystem::path& base_dir, const SceneLoadOptions& options) {
  auto src = std::make_shared<JsonSource>(JsonSource{display_name, base_dir});
  Json root = parse_json_text(json, display_name);
  apply_scene_overrides(root, options.overrides, display_name);
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

std::unique_ptr<Scene> load_gltf_file(const std::filesystem::path& file, const SceneLoadOptions& options) {
  if (!options.overrides.empty())
    throw InputError(file.string(), "",
                     fmt::format("-D {}: overrides apply to kozu JSON scenes, not to glTF files (a kozu scene can "
                                 "load the file as a shape of type \"gltf\")",
                                 options.overrides.front().text));
  std::filesystem::path base = file.parent_path();
  if (base.empty()) base = ".";
  auto src = std::make_shared<JsonSource>(JsonSource{file.string(), base});
  const Json root = {{"shapes", Json::array({{{"type", "gltf"}, {"file", file.filename().string()}}})}};
  SceneDesc desc = parse_scene(JsonObject(root, "", src), options, true);
  load_files(desc);
  expand_gltf(desc);
  // The default environment, only when the file brings no light of its own.
  if (desc.gltf_lights == 0) {
    static const Json sky = {{"type", "environment"}, {"radiance", 1.0}};
    desc.lights.push_back({"<default environment>", parse_light(JsonObject(sky, "", src))});
  }
  auto scene = build_scene(desc, *src);
  scene->input_files.insert(scene->input_files.begin(), file);
  return scene;
}

std::string_view demo_scene_json() { return kDemoSceneJson; }

std::unique_ptr<Scene> load_demo_scene(const SceneLoadOptions& options) {
  return load_scene_text(kDemoSceneJson, "<demo>", std::filesystem::current_path(), options);
}

}  // namespace kozu
