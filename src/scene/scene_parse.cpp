// The scene loader's parse phase (scene_loader.h): the scene's files read and checked, every name resolved,
// into a SceneDesc (scene_desc.h); no file but the scene's own is opened.
#include "scene/scene_desc.h"

#include "core/file_io.h"
#include "core/input_bounds.h"
#include "geometry/shape_registry.h"

#include <algorithm>

namespace kozu::scene_load {

namespace {

// The "camera" block as a Camera; the name of its "medium", if any, into *medium (resolved with the media).
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
  if (s.has("camera_visible")) d.camera_visible = s.get_bool("camera_visible");
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

}  // namespace

// Parse: every key is read and checked and every name resolved before any file is opened. `layers` are the scene's
// files: those it includes (depth first, in order), then the scene file itself (last); named models of all of them
// share one namespace, their shapes and lights add up.
SceneDesc parse_scene(const std::vector<JsonObject>& layers, const SceneLoadOptions& options, bool gltf_direct) {
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

}  // namespace kozu::scene_load
