#include "scene/scene_loader.h"

#include "core/error.h"
#include "core/file_io.h"
#include "core/input_bounds.h"
#include "core/json_reader.h"
#include "geometry/instance.h"
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
#include <map>
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

  std::vector<std::string> files;  // the scene file that defined each name (with "include", one of several)

  explicit Named(const char* kind_name) : kind(kind_name) {}
  // Reads root[key] (an object of name: description), parsing each description with parse. A name one of the
  // scene's other files (include) already defined is an error naming both.
  template <class Parse>
  void parse(const JsonObject& root, std::string_view key, Parse&& parse_one) {
    if (!root.has(key)) return;
    const JsonObject all = root.get_object(key);
    for (const std::string& name : all.keys()) {
      check_new(name, all.source().display_name, all.path_of(name));
      models.push_back(parse_one(all.get_object(name)));
      names.push_back(name);
      files.push_back(all.source().display_name);
    }
  }
  void check_new(const std::string& name, const std::string& file, const std::string& json_path) const {
    for (size_t i = 0; i < names.size(); ++i)
      if (names[i] == name && i < files.size())
        throw InputError(file, json_path,
                         fmt::format("{} '{}' is defined twice: in {} and in {}", kind, name, files[i], file));
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
  GltfScene scene;         // filled by the load job
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
  std::optional<size_t> object;    // type "instance": the object it places (by placement)
  bool ellipsoid = false;          // a sphere whose transform does not keep angles: placed through an instance
  bool by_name = false;            // an OBJ mesh whose usemtl groups name the scene's materials
  std::string file;                // the scene file that describes it (with "include", one of several)
};

// One of the scene's "objects": shapes stored once, placed by "instance" shapes (geometry/instance.h).
struct ObjectDesc {
  std::vector<ShapeDesc> shapes;
  std::shared_ptr<const InstancedObject> built;  // filled by the build phase
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
  std::vector<std::string> object_names;
  std::vector<ObjectDesc> objects;
  std::vector<LightDesc> lights;
  MaterialParseContext material_ctx;
  std::vector<std::string> warnings;
  // A glTF file rendered directly (load_gltf_file): its camera, its lights, the bounds of its meshes.
  std::vector<SourcePtr> sources;  // the scene's files (include): their warnings and the files they name
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
  Vec3 position, look_at, up;
  std::optional<float> transform_focus;
  if (c.has("transform")) {
    // Camera to world, the camera at the origin looking down -z with +y up (glTF's and OpenEXR's convention).
    for (const char* key : {"position", "look_at", "up"})
      if (c.has(key)) c.fail(key, fmt::format("give either 'transform' or position/look_at/up, not both ('{}')", key));
    const Transform t = read_transform(c.get_object("transform"));
    const Mat4& m = t.matrix();
    const Vec3 y(m[1]), z(m[2]);
    const float ly = glm::length(y), lz = glm::length(z);
    if (!t.is_similarity() || t.determinant() < 0.0f)
      c.fail("transform",
             "a camera takes rotations, translations and uniform scales only (no shear, "
             "non-uniform scale or mirror)");
    position = Vec3(m[3]);
    if (!within_bounds(position)) c.fail("transform", bounds_message(position));
    look_at = position - z / lz;
    up = y / ly;
    transform_focus = 1.0f;
  } else {
    position = get_point(c, "position");
    look_at = get_point(c, "look_at");
    up = c.get_direction("up", Vec3(0, 1, 0));
  }
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
    c.finish({"resolution", "medium", "scale", "transform"});
    return Camera::with_projection(type == "panorama" ? Camera::Projection::Panorama : Camera::Projection::Orthographic,
                                   position, look_at, up, res, scale);
  }
  if (c.has("scale"))
    c.fail("scale", "'scale' is the height of an orthographic camera: add \"type\": \"orthographic\"");
  const float fov = c.get_float("fov", 40.0f, Range{0.0, 180.0, true, true});
  float aperture = 0.0f, focus = glm::length(look_at - position);
  if (type == "thinlens") {
    aperture = c.get_float("aperture_radius", {}, kSizeRange);
    if (transform_focus && !c.has("focus_distance"))
      c.fail("focus_distance", "a thin-lens camera placed by 'transform' needs 'focus_distance' (it has no look_at)");
    focus = c.get_float("focus_distance", focus, kSizeRange);
  } else {
    for (const char* key : {"aperture_radius", "focus_distance"})
      if (c.has(key)) c.fail(key, fmt::format("'{}' needs a thin-lens camera: add \"type\": \"thinlens\"", key));
  }
  if (c.has("medium")) *medium = c.get_string("medium");
  c.finish({"aperture_radius", "focus_distance", "resolution", "medium", "transform"});
  return Camera(position, look_at, up, fov, res, aperture, focus);
}

// A shape's shared keys (material, emission, media), then its geometry (geometry/shape_registry.h).
// A "gltf" shape (docs/scene-format.md): the file, its placement and its light units; materials, emission and
// media come from the file.
ShapeDesc parse_gltf_desc(const JsonObject& s, const SceneLoadOptions& options) {
  ShapeDesc d;
  d.type = "gltf";
  d.json_path = s.path();
  d.file = s.source().display_name;
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

// An "instance" shape: an object of the scene's "objects" (by name) and its placement.
ShapeDesc parse_instance_desc(const JsonObject& s, const std::vector<std::string>& objects) {
  ShapeDesc d;
  d.type = "instance";
  d.json_path = s.path();
  d.file = s.source().display_name;
  const std::string name = s.get_string("object");
  const auto it = std::find(objects.begin(), objects.end(), name);
  if (it == objects.end()) {
    std::string known;
    for (const std::string& k : objects) known += (known.empty() ? "'" : ", '") + k + "'";
    s.fail("object",
           fmt::format("unknown object '{}' (defined in \"objects\": {})", name, known.empty() ? "none" : known));
  }
  d.object = static_cast<size_t>(it - objects.begin());
  for (const char* key : {"material", "emission", "two_sided", "interior", "exterior"})
    if (s.has(key))
      s.fail(key, fmt::format("an instance takes its materials and media from its object's shapes: remove '{}'", key));
  if (s.has("transform")) d.placement = read_transform(s.get_object("transform")).matrix();
  if (s.has("name")) d.name = s.get_string("name");
  s.get_enum("type", {"instance"});
  s.finish();
  return d;
}

ShapeDesc parse_shape_desc(const JsonObject& s, const Named<Material>& materials, const Named<Medium>& media,
                           const SceneLoadOptions& options, const std::function<TextureCache*()>& textures,
                           const std::vector<std::string>& objects) {
  if (s.has("type") && s.raw("type") == "gltf") return parse_gltf_desc(s, options);
  if (s.has("type") && s.raw("type") == "instance") return parse_instance_desc(s, objects);
  ShapeDesc d;
  d.json_path = s.path();
  d.file = s.source().display_name;
  const JsonSource& src = s.source();
  d.by_name = s.has("materials_by_name") && s.raw("materials_by_name") == true;
  if (s.has("emission") && s.has("power")) s.fail("power", "give either 'emission' or 'power' (watts), not both");
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
  } else if (is_black(d.emission) && !d.interior && !d.exterior && !d.by_name) {
    s.fail("missing required key 'material' (only emitters and medium boundaries may omit it)");
  }
  if (s.has("name")) d.name = s.get_string("name");
  d.shape = parse_shape(s, &d.type);
  if (s.has("transform")) {
    const Transform t = read_transform(s.get_object("transform"));
    d.placement = t.matrix();
    if (d.type == "sphere" && !t.is_similarity()) {
      // An ellipsoid: the sphere as given, placed through an instance (parse_sphere applied no transform).
      if (!is_black(d.emission))
        s.fail("transform",
               "an emitting sphere takes rotations, translations and uniform scales only (its light "
               "samples a sphere); use an emitting mesh for an ellipsoid");
      d.ellipsoid = true;
    }
  }
  return d;
}

// The shapes of one object (an "objects" entry): as top-level shapes, but stored once and placed by instances,
// so they cannot emit (an area light samples one surface in world space), be glTF files or instances, or move.
std::vector<ShapeDesc> parse_object_shapes(const JsonArray& shapes, const Named<Material>& materials,
                                           const Named<Medium>& media, const SceneLoadOptions& options,
                                           const std::function<TextureCache*()>& textures) {
  std::vector<ShapeDesc> out;
  if (shapes.size() == 0) shapes.fail("an object needs at least one shape");
  for (size_t i = 0; i < shapes.size(); ++i) {
    const JsonObject s = shapes.object(i);
    if (s.has("type") && (s.raw("type") == "gltf" || s.raw("type") == "instance"))
      s.fail("type", fmt::format("an object's shapes cannot be of type '{}' (objects do not nest)",
                                 s.raw("type").get<std::string>()));
    if (s.has("power")) s.fail("power", "an object's shapes cannot emit light: make the emitter a shape of its own");
    if (s.has("emission"))
      s.fail("emission",
             "an object's shapes cannot emit light (an area light is one surface in the scene): make "
             "the emitter a shape of its own");
    if (s.has("name")) s.fail("name", "an object's shapes are not named: name the instance that places them");
    out.push_back(parse_shape_desc(s, materials, media, options, textures, {}));
    if (out.back().ellipsoid)
      s.fail("transform",
             "an object's sphere takes rotations, translations and uniform scales only (an ellipsoid "
             "is itself an instance, and instances do not nest); use a mesh");
  }
  return out;
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

// Each shape track of the animation to the one shape of its name, which must be able to move: not mirrored by its
// own transform, a sphere only under uniform scales. An emitter moves with its area lights (Light::refit).
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

// The top-level keys a scene file may hold.
const std::vector<std::string> kSceneKeys = {"include", "camera",  "render", "animation", "materials",
                                             "media",   "objects", "shapes", "lights"};

// The one file among `layers` that holds `key` (camera, render, animation), if any; two are an error naming both.
const JsonObject* single_holder(const std::vector<JsonObject>& layers, std::string_view key) {
  const JsonObject* found = nullptr;
  for (const JsonObject& l : layers)
    if (l.has(key)) {
      if (found)
        l.fail(key, fmt::format("'{}' is given twice: in {} and in {} (an included file and the file that "
                                "includes it may not both set it)",
                                key, found->source().display_name, l.source().display_name));
      found = &l;
    }
  return found;
}

// Parse: every key is read and checked and every name resolved before any file is opened. `layers` are the scene's
// files: those it includes (depth first, in order), then the scene file itself (last); named models of all of them
// share one namespace, their shapes and lights add up.
SceneDesc parse_scene(const std::vector<JsonObject>& layers, const SceneLoadOptions& options,
                      bool gltf_direct = false) {
  const JsonObject& root = layers.back();
  SceneDesc d;
  d.gltf_direct = gltf_direct;
  // Made when the first image texture is parsed: most scenes have none.
  const auto textures = [&d, &options]() {
    if (!d.textures) d.textures = std::make_unique<TextureCache>(options.textures);
    return d.textures.get();
  };
  std::string camera_medium;
  const JsonObject* camera_file = single_holder(layers, "camera");
  // A glTF file rendered directly gets its camera after loading (build_scene).
  if (!gltf_direct) d.camera = parse_camera((camera_file ? *camera_file : root).get_object("camera"), &camera_medium);
  if (const JsonObject* r = single_holder(layers, "render"))
    d.settings = parse_render_settings(r->get_object("render"));
  if (const JsonObject* a = single_holder(layers, "animation")) {
    if (gltf_direct) a->fail("animation", "a glTF file rendered directly has no animation block");
    d.animation = parse_animation(a->get_object("animation"), camera_key(d.camera));
  }
  d.material_ctx = MaterialParseContext{textures};
  for (const JsonObject& l : layers)
    d.materials.parse(l, "materials", [&](const JsonObject& m) { return parse_material(m, d.material_ctx); });
  for (const JsonObject& l : layers) d.media.parse(l, "media", &parse_medium);
  if (!camera_medium.empty()) d.camera_medium = d.media.index(camera_medium, camera_file->source(), "/camera/medium");
  std::vector<std::string> object_files;
  for (const JsonObject& l : layers) {
    if (!l.has("objects")) continue;
    const JsonObject objects = l.get_object("objects");
    for (const std::string& name : objects.keys()) {
      for (size_t i = 0; i < d.object_names.size(); ++i)
        if (d.object_names[i] == name)
          objects.fail(name, fmt::format("object '{}' is defined twice: in {} and in {}", name, object_files[i],
                                         l.source().display_name));
      d.object_names.push_back(name);
      object_files.push_back(l.source().display_name);
      d.objects.push_back({parse_object_shapes(objects.get_array(name), d.materials, d.media, options, textures)});
    }
  }
  bool have_shapes = false;
  for (const JsonObject& l : layers) {
    if (!l.has("shapes")) continue;
    have_shapes = true;
    const JsonArray shapes = l.get_array("shapes");
    for (size_t i = 0; i < shapes.size(); ++i)
      d.shapes.push_back(parse_shape_desc(shapes.object(i), d.materials, d.media, options, textures, d.object_names));
  }
  if (!have_shapes) root.get_array("shapes");  // "missing required key 'shapes'"
  resolve_shape_tracks(d, root.source());
  bool have_env = false;
  for (const JsonObject& l : layers) {
    if (!l.has("lights")) continue;
    const JsonArray lights = l.get_array("lights");
    for (size_t i = 0; i < lights.size(); ++i) {
      std::string type;
      // Messages name a light by its path; an included file's by its file too.
      d.lights.push_back({&l == &root ? lights.path_of(i) : l.source().display_name + ": " + lights.path_of(i),
                          parse_light(lights.object(i), &type)});
      if (type == "environment" && have_env) lights.fail(i, "only one environment light is allowed");
      have_env |= type == "environment";
    }
  }
  for (const JsonObject& l : layers) {
    if (l.has("include")) l.raw("include");  // read by collect_includes
    l.finish(kSceneKeys);
  }
  for (const JsonObject& l : layers) d.sources.push_back(l.source_ptr());
  return d;
}

// Load: the files every model needs, all at once.
void load_files(SceneDesc& d) {
  std::vector<std::function<void()>> jobs;
  for (Deferred<Material>& m : d.materials.models) add_load_job(m, jobs);
  for (Deferred<Medium>& m : d.media.models) add_load_job(m, jobs);
  for (ObjectDesc& o : d.objects)
    for (ShapeDesc& s : o.shapes) add_load_job(s.shape, jobs);
  for (ShapeDesc& s : d.shapes) {
    add_load_job(s.shape, jobs);
    if (s.emission_texture) add_load_job(*s.emission_texture, jobs);
    if (s.gltf) {
      jobs.emplace_back([&s, direct = d.gltf_direct] {
        try {
          // A keyed pose replaces the shape's transform under each node: meshes are then copied, not instanced.
          s.gltf->options.instance_meshes = !s.track;
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
// messages name the glTF file and its own JSON paths (GltfScene::gltf_path), and their textures prepared in
// parallel. A mesh several nodes use becomes one of the scene's objects, placed by instances. The files the glTF
// reads (buffers, images) are inputs of the render.
void expand_gltf(SceneDesc& d) {
  std::vector<ShapeDesc> shapes;
  std::vector<std::function<void()>> jobs;
  std::vector<std::shared_ptr<GltfDesc>> files;
  const size_t first_material = d.materials.models.size(), first_light = d.lights.size();
  // Runs f, a message about a glTF's kozu description turned into one naming the glTF's own JSON path.
  const auto in_gltf_terms = [&files](const auto& f) {
    try {
      f();
    } catch (const InputError& e) {
      for (const auto& g : files)
        if (e.file() == g->file.string()) {
          const std::string prefix = InputError::format(e.file(), e.json_path(), "");
          const std::string what = e.what();
          throw InputError(e.file(), g->scene.gltf_path(e.json_path()),
                           what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what);
        }
      throw;
    }
  };
  for (ShapeDesc& sd : d.shapes) {
    if (!sd.gltf) {
      shapes.push_back(std::move(sd));
      continue;
    }
    files.push_back(sd.gltf);
    GltfScene& g = sd.gltf->scene;
    const std::filesystem::path& file = sd.gltf->file;
    auto src = std::make_shared<JsonSource>(JsonSource{file.string(), file.parent_path()});
    src->files = g.input_files;
    d.sources.push_back(src);
    for (const std::string& w : g.warnings) d.warnings.push_back(w);
    const size_t material_base = d.materials.models.size();
    in_gltf_terms([&] {
      for (size_t i = 0; i < g.materials.size(); ++i) {
        Json& m = g.materials[i];
        d.materials.models.push_back(
            parse_material(JsonObject(m, fmt::format("/materials/{}", i), src), d.material_ctx));
        d.materials.names.push_back(file.filename().string() + ":" + g.material_names[i]);
      }
    });
    std::vector<std::optional<size_t>> interior(g.media.size());
    in_gltf_terms([&] {
      for (size_t i = 0; i < g.media.size(); ++i) {
        if (g.media[i].is_null()) continue;
        interior[i] = d.media.models.size();
        d.media.models.push_back(
            parse_medium(JsonObject(g.media[i], fmt::format("/materials/{}/extensions/KHR_materials_volume", i), src)));
        d.media.names.push_back(file.filename().string() + ":" + g.material_names[i]);
      }
    });
    size_t triangles = 0;
    // A primitive as a mesh shape (degenerate triangles dropped); false when nothing is left of it.
    const auto mesh_desc = [&](GltfPrimitive& p, ShapeDesc& s) {
      MeshData& mesh = p.mesh;
      // Zero-area triangles are common in exported assets and invisible: dropped.
      remove_degenerate_triangles(mesh);
      if (mesh.indices.empty()) return false;
      triangles += mesh.indices.size() / 3;
      s.type = "mesh";
      s.json_path = sd.json_path + p.json_path;
      s.material = material_base + size_t(p.material);
      s.interior = interior[size_t(p.material)];
      s.file = sd.file;
      s.shape = std::make_unique<TriangleMesh>(std::move(mesh.positions), std::move(mesh.indices),
                                               std::move(mesh.normals), std::move(mesh.uvs), std::move(mesh.tangents));
      return true;
    };
    for (GltfPrimitive& p : g.primitives) {
      for (const Vec3& v : p.mesh.positions) {
        d.lo = glm::min(d.lo, v);
        d.hi = glm::max(d.hi, v);
      }
      ShapeDesc s;
      if (!mesh_desc(p, s)) continue;
      s.emission = g.emission[size_t(p.material)];
      s.two_sided = g.double_sided[size_t(p.material)];
      s.name = sd.name;
      s.placement = sd.placement;
      s.track = sd.track;
      shapes.push_back(std::move(s));
    }
    // Meshes several nodes use (never emitting ones: GltfScene::objects): stored once, placed by instances.
    std::vector<std::optional<size_t>> object_index(g.objects.size());
    std::vector<std::pair<Vec3, Vec3>> object_bounds(g.objects.size(), {Vec3(kInfinity), Vec3(-kInfinity)});
    for (size_t o = 0; o < g.objects.size(); ++o) {
      ObjectDesc object;
      const size_t before = triangles;
      for (GltfPrimitive& p : g.objects[o].primitives) {
        for (const Vec3& v : p.mesh.positions) {
          object_bounds[o].first = glm::min(object_bounds[o].first, v);
          object_bounds[o].second = glm::max(object_bounds[o].second, v);
        }
        ShapeDesc s;
        if (mesh_desc(p, s)) object.shapes.push_back(std::move(s));
      }
      triangles = before;  // counted by its instances below
      if (object.shapes.empty()) continue;
      object_index[o] = d.objects.size();
      d.object_names.push_back(file.filename().string() + ":" + g.objects[o].name);
      d.objects.push_back(std::move(object));
    }
    for (const GltfInstance& inst : g.instances) {
      if (!object_index[inst.object]) continue;
      ++triangles;  // the object holds triangles (empty ones were left out): enough to know something is drawn
      const auto& [lo, hi] = object_bounds[inst.object];
      for (int c = 0; c < 8; ++c) {
        const Vec3 w(inst.transform * Vec4(c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z, 1.0f));
        d.lo = glm::min(d.lo, w);
        d.hi = glm::max(d.hi, w);
      }
      ShapeDesc s;
      s.type = "instance";
      s.json_path = sd.json_path + inst.json_path;
      s.object = object_index[inst.object];
      s.name = sd.name;
      s.file = sd.file;
      s.placement = inst.transform;
      shapes.push_back(std::move(s));
    }
    // A file that yields nothing to see is an error, not an empty image.
    if (triangles == 0 && (d.gltf_direct || g.lights.empty()))
      throw InputError(file.string(), "",
                       "the file yields no triangle to render (its scene's meshes are missing, points or lines only, "
                       "or of zero area)");
    for (size_t i = 0; i < g.lights.size(); ++i) {
      const std::string path = g.gltf_path(fmt::format("/lights/{}", i));
      in_gltf_terms([&] {
        d.lights.push_back({fmt::format("{}: {}", file.string(), path),
                            parse_light(JsonObject(g.lights[i], fmt::format("/lights/{}", i), src))});
      });
      ++d.gltf_lights;
    }
    if (g.camera && !d.gltf_camera) d.gltf_camera = g.camera;
  }
  d.shapes = std::move(shapes);
  for (size_t i = first_material; i < d.materials.models.size(); ++i) add_load_job(d.materials.models[i], jobs);
  for (size_t i = first_light; i < d.lights.size(); ++i) add_load_job(d.lights[i].light, jobs);
  in_gltf_terms([&] { load_all(jobs); });
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
  // A shape's material, media, cut-out and tangents, and the warnings about it.
  const auto dress = [&](Shape* shape, const ShapeDesc& sd, std::optional<size_t> material) {
    shape->material = material ? d.materials.built[*material] : nullptr;
    // An open boundary lets paths into a medium or a subsurface material that never find the way out (or out of
    // one they never entered): not an error (a ground plane may rightly bound an atmosphere), but said.
    const bool subsurface = shape->material && shape->material->has_subsurface();
    if (sd.interior || sd.exterior || subsurface)
      if (const size_t open = shape->open_edges(); open > 0)
        scene->warnings.push_back(InputError::format(
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
    shape->interior = sd.interior ? d.media.built[*sd.interior] : nullptr;
    shape->exterior = sd.exterior ? d.media.built[*sd.exterior] : nullptr;
  };
  // A shape as built, or, for an OBJ mesh with "materials_by_name", one mesh per usemtl name with the scene's
  // material of that name (faces before any usemtl: the shape's own "material").
  const auto pieces = [&](ShapeDesc& sd) {
    std::vector<std::pair<std::unique_ptr<Shape>, std::optional<size_t>>> out;
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
  };
  for (size_t o = 0; o < d.objects.size(); ++o) {
    std::vector<std::unique_ptr<Shape>> shapes;
    for (size_t i = 0; i < d.objects[o].shapes.size(); ++i) {
      ShapeDesc& sd = d.objects[o].shapes[i];
      for (auto& [shape, material] : pieces(sd)) {
        shape->name = fmt::format("objects.{}[{}]", d.object_names[o], i);
        dress(shape.get(), sd, material);
        shapes.push_back(std::move(shape));
      }
    }
    d.objects[o].built = std::make_shared<const InstancedObject>(std::move(shapes));
  }
  // Instances are small, but a scene may place millions of them: their memory is checked before any is created.
  size_t instance_count = 0;
  for (const ShapeDesc& sd : d.shapes) instance_count += sd.object || sd.ellipsoid ? 1 : 0;
  check_instance_memory(instance_count, src.display_name, "/shapes");
  for (size_t i = 0; i < d.shapes.size(); ++i) {
    ShapeDesc& sd = d.shapes[i];
    std::vector<std::pair<std::unique_ptr<Shape>, std::optional<size_t>>> built;
    if (sd.object)
      built.emplace_back(std::make_unique<Instance>(d.objects[*sd.object].built, sd.placement), std::nullopt);
    else
      built = pieces(sd);
    for (auto& [shape, material] : built) {
      shape->name = fmt::format("shapes[{}]", i);
      if (!sd.object) dress(shape.get(), sd, material);
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
  // A keyed emitter at each of its keys (where a linearly keyed scale is largest, as a rule; every frame is checked
  // again when it is posed), before any frame is rendered.
  for (const Scene::AnimatedShape& a : scene->animated_shapes) {
    if (a.lights.empty()) continue;
    const ShapeTrack& track = scene->animation.shapes[a.track];
    for (size_t k = 0; k < track.keys.size(); ++k) {
      try {
        scene->pose_shapes(track.keys[k].time);
      } catch (const std::invalid_argument& e) {
        throw InputError(src.display_name, json_pointer_append(track.json_path, k), e.what());
      }
    }
  }
  if (std::none_of(scene->lights.begin(), scene->lights.end(),
                   [](const auto& l) { return max_component(l->power()) > 0.0f; }))
    scene->warnings.push_back(
        fmt::format("{}: the scene has no light{}, so the image is black: add a light, an emissive shape or an "
                    "environment",
                    src.display_name, scene->lights.empty() ? "" : " that emits"));
  return scene;
}

// A scene's files: those `file` includes ("include": [paths relative to it]), depth first, then itself. A file
// included twice (a cycle, or two files including one) is an error naming both includers; at most
// kMaxIncludedFiles files in all.
struct SceneFiles {
  std::vector<std::unique_ptr<Json>> json;  // stable addresses: JsonObjects point into them
  std::vector<JsonObject> layers;
  std::vector<std::filesystem::path> included;        // every included file (the render's inputs)
  std::map<std::filesystem::path, std::string> seen;  // canonical path -> the file that included it
};
constexpr size_t kMaxIncludedFiles = 256;

void collect_includes(const JsonObject& file, SceneFiles& files, std::vector<std::filesystem::path>& chain) {
  if (file.has("include")) {
    const Json& list = file.raw("include");
    if (!list.is_array()) file.fail("include", "expected an array of scene files");
    const JsonArray entries = file.get_array("include");
    for (size_t i = 0; i < entries.size(); ++i) {
      if (!entries.raw(i).is_string() || entries.raw(i).get<std::string>().empty())
        entries.fail(i, "expected the path of a scene file");
      const std::filesystem::path& dir = file.source().base_dir;
      const std::filesystem::path path = dir == "." ? std::filesystem::path(entries.raw(i).get<std::string>())
                                                    : dir / entries.raw(i).get<std::string>();
      std::error_code ec;
      const std::filesystem::path canonical = std::filesystem::weakly_canonical(path, ec);
      const std::filesystem::path key = ec ? path : canonical;
      for (const std::filesystem::path& c : chain)
        if (c == key)
          entries.fail(i, fmt::format("{} includes itself through the chain of includes (a cycle)", path.string()));
      if (const auto it = files.seen.find(key); it != files.seen.end())
        entries.fail(i, fmt::format("{} is included twice: by {} and by {} (its names would be defined twice)",
                                    path.string(), it->second, file.source().display_name));
      if (files.seen.size() >= kMaxIncludedFiles)
        entries.fail(i, fmt::format("more than {} included files", kMaxIncludedFiles));
      files.seen.emplace(key, file.source().display_name);
      std::string text;
      try {
        text = read_input_file(path);
      } catch (const InputError& e) {
        entries.fail(i, e.what());
      }
      std::filesystem::path base = path.parent_path();
      if (base.empty()) base = ".";
      auto src = std::make_shared<JsonSource>(JsonSource{path.string(), base});
      files.json.push_back(std::make_unique<Json>(parse_json_text(text, path.string())));
      if (!files.json.back()->is_object()) throw InputError(path.string(), "", "expected a JSON object (a scene file)");
      files.included.push_back(path);
      const JsonObject included(*files.json.back(), "", src);
      chain.push_back(key);
      collect_includes(included, files, chain);
      chain.pop_back();
      files.layers.push_back(included);
    }
  }
}

std::unique_ptr<Scene> load_from_json(const Json& root_json, const SourcePtr& src, const SceneLoadOptions& options) {
  SceneFiles files;
  const JsonObject root(root_json, "", src);
  std::vector<std::filesystem::path> chain;
  std::error_code ec;
  if (const auto self = std::filesystem::weakly_canonical(src->display_name, ec); !ec) chain.push_back(self);
  collect_includes(root, files, chain);
  files.layers.push_back(root);
  SceneDesc desc = parse_scene(files.layers, options);
  load_files(desc);
  expand_gltf(desc);
  auto scene = build_scene(desc, *src);
  scene->input_files.insert(scene->input_files.begin(), files.included.begin(), files.included.end());
  return scene;
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
  SceneDesc desc = parse_scene({JsonObject(root, "", src)}, options, true);
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
