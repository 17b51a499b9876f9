#include "scene/scene_loader.h"

#include "core/error.h"
#include "core/file_io.h"
#include "core/json_reader.h"
#include "core/transform.h"
#include "geometry/mesh_cleanup.h"
#include "geometry/polygon.h"
#include "io/image_io.h"
#include "io/mesh_io.h"
#include "lights/area.h"
#include "lights/environment.h"
#include "lights/point.h"
#include "lights/spot.h"
#include "media/medium.h"
#include "scene/render_settings.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <fstream>
#include <map>
#include <optional>
#include <sstream>

namespace kozu {

extern const std::string_view kDemoSceneJson;

namespace {

using SourcePtr = std::shared_ptr<const JsonSource>;

// Radiometric bounds: values beyond them overflow float arithmetic on a path (radiance × throughput / pdf) or in
// a light's power, far beyond anything physical in any unit.
constexpr double kMaxRadiance = 1e30;
constexpr float kMaxLightPower = 1e30f;
// Positions and sizes: float arithmetic on them (squared distances, areas, error bounds) must stay finite, and
// Embree takes coordinates within ±1.8e18.
constexpr double kMaxCoordinate = 1e15;
const Range kSizeRange{0.0, kMaxCoordinate, true, false};

bool within_bounds(const Vec3& p) { return double(max_component(glm::abs(p))) <= kMaxCoordinate; }
std::string bounds_message(const Vec3& p) {
  return fmt::format("coordinates must lie within ±{:g}, got ({:g}, {:g}, {:g})", kMaxCoordinate, p.x, p.y, p.z);
}
// A position: a vec3 within the coordinate bounds.
Vec3 get_point(const JsonObject& o, std::string_view key) {
  const Vec3 p = o.get_vec3(key);
  if (!within_bounds(p)) o.fail(key, bounds_message(p));
  return p;
}

// ---------------------------------------------------------------------------------------------
// Descriptions produced by the parse phase.

struct ShapeDesc {
  std::string type;                // sphere | quad | polygon | mesh
  std::string json_path;           // "/shapes/3"
  std::string material;            // empty: none (only allowed for emitters and medium boundaries)
  std::string interior, exterior;  // media names, empty: none
  Rgb emission{0.0f};
  bool two_sided = false;
  // sphere
  Vec3 center{0.0f};
  float radius = 0;
  // quad / polygon / inline mesh
  MeshData inline_mesh;
  // mesh file
  std::filesystem::path file;
  std::string file_json_path;
  Transform transform;
  bool has_transform = false;
  bool skip_degenerate = false;
};

// ---------------------------------------------------------------------------------------------
// Small helpers.

// Checks the polygon's vertices against the coordinate bounds, then triangulates it (geometry/polygon.h).
MeshData polygon_mesh(const std::vector<Vec3>& v, const JsonObject& shape) {
  for (const Vec3& p : v)
    if (!within_bounds(p))
      shape.fail("vertices", bounds_message(p) + (shape.has("transform") ? " after the transform" : ""));
  MeshData mesh;
  try {
    mesh.indices = triangulate_polygon(v);
  } catch (const PolygonError& e) {
    shape.fail("vertices", e.what());
  }
  mesh.positions = v;
  return mesh;
}

// Applies the transform, checks the vertices and removes (or rejects) degenerate triangles.
void finalize_mesh(MeshData& mesh, const ShapeDesc& d, const JsonSource& src) {
  if (d.has_transform) transform_mesh(mesh, d.transform);
  for (const Vec3& p : mesh.positions)
    if (!is_finite(p) || !within_bounds(p))
      throw InputError(src.display_name, d.json_path,
                       fmt::format("mesh vertex {}: {}", static_cast<size_t>(&p - mesh.positions.data()),
                                   bounds_message(p) + (d.has_transform ? " after the transform" : "")));
  if (!d.skip_degenerate)
    if (const std::optional<size_t> t = first_degenerate_triangle(mesh))
      throw InputError(src.display_name, d.file.empty() ? d.json_path : d.file_json_path,
                       fmt::format("{}triangle {} is degenerate (zero area); set \"skip_degenerate\": true to drop "
                                   "such triangles",
                                   d.file.empty() ? "" : d.file.filename().string() + ": ", *t));
  remove_degenerate_triangles(mesh);
  if (mesh.indices.empty()) throw InputError(src.display_name, d.json_path, "mesh has no triangles");
}

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

ShapeDesc parse_shape(const JsonObject& s) {
  ShapeDesc d;
  d.json_path = s.path();
  d.type = s.get_enum("type", {"sphere", "quad", "polygon", "mesh"});
  if (s.has("emission")) d.emission = s.get_rgb("emission", {}, Range::non_negative());
  if (s.has("two_sided")) d.two_sided = s.get_bool("two_sided");
  if (s.has("interior")) d.interior = s.get_string("interior");
  if (s.has("exterior")) d.exterior = s.get_string("exterior");
  if (s.has("material")) {
    d.material = s.get_string("material");
    if (d.material.empty()) s.fail("material", "expected a material name");
  } else if (is_black(d.emission) && d.interior.empty() && d.exterior.empty()) {
    s.fail("missing required key 'material' (only emitters and medium boundaries may omit it)");
  }
  s.ignore("name");
  if (d.type == "sphere") {
    d.center = get_point(s, "center");
    d.radius = s.get_float("radius", {}, kSizeRange);
  } else if (d.type == "quad" || d.type == "polygon") {
    const JsonArray verts = s.get_array("vertices");
    if (d.type == "quad" && verts.size() != 4)
      verts.fail(fmt::format("a quad needs exactly 4 vertices, got {}", verts.size()));
    if (verts.size() < 3) verts.fail(fmt::format("a polygon needs at least 3 vertices, got {}", verts.size()));
    std::vector<Vec3> v(verts.size());
    for (size_t i = 0; i < v.size(); ++i) v[i] = verts.vec3(i);
    if (s.has("transform")) {
      const Transform t = read_transform(s.get_object("transform"));
      for (Vec3& p : v) p = t.point(p);
      // Mirroring transforms reverse the winding: restore the intended front side.
      if (t.determinant() < 0.0f) std::reverse(v.begin(), v.end());
    }
    d.inline_mesh = polygon_mesh(v, s);
  } else {  // mesh
    if (s.has("file")) {
      d.file = s.get_path("file");
      d.file_json_path = s.path_of("file");
      if (s.has("positions")) s.fail("positions", "give either 'file' or inline 'positions'/'indices', not both");
    } else {
      const JsonArray pos = s.get_array("positions");
      const JsonArray idx = s.get_array("indices");
      for (size_t i = 0; i < pos.size(); ++i) d.inline_mesh.positions.push_back(pos.vec3(i));
      if (idx.size() % 3 != 0 || idx.size() == 0) idx.fail("expected a nonzero multiple of 3 vertex indices");
      const Range vertex{0.0, static_cast<double>(pos.size()), false, true};
      for (size_t i = 0; i < idx.size(); ++i)
        d.inline_mesh.indices.push_back(static_cast<uint32_t>(idx.integer(i, vertex)));
      if (s.has("normals")) {
        const JsonArray nrm = s.get_array("normals");
        if (nrm.size() != pos.size()) nrm.fail("expected one normal per position");
        for (size_t i = 0; i < nrm.size(); ++i) d.inline_mesh.normals.push_back(nrm.vec3(i));
      }
    }
    if (s.has("transform")) {
      d.transform = read_transform(s.get_object("transform"));
      d.has_transform = true;
    }
    d.skip_degenerate = s.get_bool("skip_degenerate", false);
  }
  s.finish();
  return d;
}

std::unique_ptr<Light> parse_light(const JsonObject& l, const SourcePtr& src, bool* is_environment) {
  const std::string type = l.get_enum("type", {"environment", "point", "spot"});
  *is_environment = type == "environment";
  std::unique_ptr<Light> light;
  if (type == "environment") {
    if (l.has("file") == l.has("radiance"))
      l.fail("give exactly one of 'radiance' (uniform) or 'file' (lat-long image)");
    if (l.has("radiance")) {
      const Rgb radiance = l.get_rgb("radiance");
      const double scale = l.get_float("scale", 1.0f, Range::non_negative());
      if (max_component(radiance) * scale > kMaxRadiance)
        l.fail("scale", fmt::format("radiance times scale is {:.3g}, beyond kozu's range (at most {:g})",
                                    max_component(radiance) * scale, kMaxRadiance));
      light = std::make_unique<EnvironmentLight>(radiance * static_cast<float>(scale));
    } else {
      const std::filesystem::path file = l.get_path("file");
      const float scale = l.get_float("scale", 1.0f, Range::non_negative());
      const float rotate = l.get_float("rotate", 0.0f);
      Image img;
      try {
        img = read_image(file);
      } catch (const InputError& e) {
        throw InputError(src->display_name, l.path_of("file"), e.what());
      }
      // Radiance is >= 0, and scaled it must stay within float range (checked in double).
      for (size_t i = 0; i < img.data.size(); ++i) {
        const double v = img.data[i];
        const size_t pixel = i / static_cast<size_t>(img.channels);
        const auto where = [&] {
          return fmt::format("{}: pixel ({}, {}) channel {}", file.string(), pixel % static_cast<size_t>(img.width),
                             pixel / static_cast<size_t>(img.width), i % static_cast<size_t>(img.channels));
        };
        if (v < 0.0) l.fail("file", fmt::format("{} is negative ({}); radiance must be >= 0", where(), v));
        if (v * scale > kMaxRadiance)
          l.fail("scale", fmt::format("{} times scale is {:.3g}, beyond kozu's range (at most {:g})", where(),
                                      v * scale, kMaxRadiance));
      }
      light = std::make_unique<EnvironmentLight>(img.to_rgb(), img.width, img.height, scale, rotate);
    }
  } else if (type == "point") {
    light = std::make_unique<PointLight>(get_point(l, "position"), l.get_rgb("intensity"));
  } else {
    const Vec3 pos = get_point(l, "position");
    Vec3 dir;
    if (l.has("look_at") == l.has("direction")) l.fail("give exactly one of 'look_at' or 'direction'");
    if (l.has("look_at")) {
      dir = get_point(l, "look_at") - pos;
      if (!(glm::dot(dir, dir) > 0.0f)) l.fail("look_at", "look_at must differ from position");
    } else {
      dir = l.get_direction("direction");
    }
    const Rgb intensity = l.get_rgb("intensity");
    const float cone = l.get_float("cone_angle", 30.0f, Range{0.0, 180.0, true, true});
    const float falloff = l.get_float("falloff_angle", std::min(25.0f, cone), Range::closed(0.0, cone));
    light = std::make_unique<SpotLight>(pos, dir, intensity, cone, falloff);
  }
  l.finish();
  return light;
}

// ---------------------------------------------------------------------------------------------
// Load + build phases.

std::unique_ptr<Scene> load_from_json(const Json& root_json, const SourcePtr& src) {
  const JsonObject root(root_json, "", src);
  auto scene = std::make_unique<Scene>();

  std::string camera_medium_name;
  scene->camera = parse_camera(root.get_object("camera"), &camera_medium_name);
  if (root.has("render")) scene->settings = parse_render_settings(root.get_object("render"));

  // Materials by name.
  std::map<std::string, const Material*> by_name;
  if (root.has("materials")) {
    const JsonObject mats = root.get_object("materials");
    for (const std::string& name : mats.keys()) {
      auto m = make_material(mats.get_object(name));
      m->name = name;
      by_name[name] = m.get();
      scene->materials.push_back(std::move(m));
    }
  }

  // Media by name.
  std::map<std::string, const Medium*> media_by_name;
  if (root.has("media")) {
    const JsonObject media = root.get_object("media");
    for (const std::string& name : media.keys()) {
      auto m = make_medium(media.get_object(name));
      m->name = name;
      media_by_name[name] = m.get();
      scene->media.push_back(std::move(m));
    }
  }
  auto find_medium = [&](const std::string& name, const std::string& json_path) -> const Medium* {
    if (name.empty()) return nullptr;
    const auto it = media_by_name.find(name);
    if (it != media_by_name.end()) return it->second;
    std::string known;
    for (const auto& [k, v] : media_by_name) known += (known.empty() ? "'" : ", '") + k + "'";
    throw InputError(src->display_name, json_path,
                     fmt::format("unknown medium '{}' (defined: {})", name, known.empty() ? "none" : known));
  };
  if (!camera_medium_name.empty()) scene->camera_medium = find_medium(camera_medium_name, "/camera/medium");

  std::vector<std::string> light_paths;  // the JSON path of each light, for messages
  // Shapes: parse all, then load mesh files in parallel, then build.
  const JsonArray shapes = root.get_array("shapes");
  std::vector<ShapeDesc> descs;
  for (size_t i = 0; i < shapes.size(); ++i) descs.push_back(parse_shape(shapes.object(i)));
  for (size_t i = 0; i < descs.size(); ++i) {
    const ShapeDesc& d = descs[i];
    if (!d.material.empty() && !by_name.count(d.material)) {
      std::string known;
      for (const auto& [k, v] : by_name) known += (known.empty() ? "'" : ", '") + k + "'";
      throw InputError(src->display_name, json_pointer_append(d.json_path, "material"),
                       fmt::format("unknown material '{}' (defined: {})", d.material, known.empty() ? "none" : known));
    }
  }
  std::vector<std::optional<InputError>> errors(descs.size());
  tbb::parallel_for(size_t{0}, descs.size(), [&](size_t i) {
    ShapeDesc& d = descs[i];
    if (d.file.empty()) return;
    try {
      d.inline_mesh = load_mesh(d.file);
    } catch (const InputError& e) {
      errors[i].emplace(src->display_name, d.file_json_path, e.what());
    } catch (const std::exception& e) {
      errors[i].emplace(src->display_name, d.file_json_path, fmt::format("{}: {}", d.file.string(), e.what()));
    }
  });
  for (const auto& e : errors)
    if (e) throw *e;  // the first failing shape in document order

  for (size_t i = 0; i < descs.size(); ++i) {
    ShapeDesc& d = descs[i];
    std::unique_ptr<Shape> shape;
    if (d.type == "sphere") {
      shape = std::make_unique<Sphere>(d.center, d.radius);
    } else {
      if (d.type == "mesh") finalize_mesh(d.inline_mesh, d, *src);
      MeshData& m = d.inline_mesh;
      shape = std::make_unique<TriangleMesh>(std::move(m.positions), std::move(m.indices), std::move(m.normals),
                                             std::move(m.uvs));
    }
    shape->name = fmt::format("shapes[{}]", i);
    shape->material = d.material.empty() ? nullptr : by_name.at(d.material);
    shape->interior = find_medium(d.interior, json_pointer_append(d.json_path, "interior"));
    shape->exterior = find_medium(d.exterior, json_pointer_append(d.json_path, "exterior"));
    if (!is_black(d.emission)) {
      if (auto* sphere = dynamic_cast<Sphere*>(shape.get())) {
        scene->lights.push_back(std::make_unique<SphereLight>(sphere, d.emission, d.two_sided));
        shape->lights.push_back(scene->lights.back().get());
      } else {
        auto* mesh = static_cast<TriangleMesh*>(shape.get());
        if (d.type == "quad" || d.type == "polygon") {
          scene->lights.push_back(std::make_unique<PolygonLight>(mesh, d.emission, d.two_sided));
          shape->lights.push_back(scene->lights.back().get());
        } else {
          for (uint32_t p = 0; p < mesh->primitive_count(); ++p) {
            scene->lights.push_back(std::make_unique<TriangleLight>(mesh, p, d.emission, d.two_sided));
            shape->lights.push_back(scene->lights.back().get());
          }
        }
      }
      light_paths.resize(scene->lights.size(), json_pointer_append(d.json_path, "emission"));
    }
    scene->shapes.push_back(std::move(shape));
  }

  if (root.has("lights")) {
    const JsonArray lights = root.get_array("lights");
    bool have_env = false;
    for (size_t i = 0; i < lights.size(); ++i) {
      bool is_env = false;
      auto light = parse_light(lights.object(i), src, &is_env);
      if (is_env && have_env) lights.fail(i, "only one environment light is allowed");
      have_env |= is_env;
      scene->lights.push_back(std::move(light));
      light_paths.push_back(lights.path_of(i));
    }
  }
  root.ignore("comment");
  root.finish({"camera", "render", "materials", "media", "shapes", "lights"});

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
