// The scene loader's internal description of a scene (scene_loader.h's three phases, split by phase over
// scene_parse.cpp, scene_load_files.cpp, scene_gltf_expand.cpp and scene_build.cpp): the structs the parse phase
// fills and the phase functions scene_loader.cpp runs in order. Not part of kozu's interface.
#pragma once

#include "core/error.h"
#include "core/json_reader.h"
#include "io/gltf_reader.h"
#include "materials/material.h"
#include "media/medium.h"
#include "scene/render_settings.h"
#include "scene/scene_loader.h"
#include "textures/texture_parse.h"

#include <fmt/format.h>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace kozu::scene_load {

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
  bool camera_visible = true;  // "camera_visible"
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

// Parse: every key is read and checked and every name resolved before any file is opened (scene_parse.cpp).
SceneDesc parse_scene(const std::vector<JsonObject>& layers, const SceneLoadOptions& options, bool gltf_direct = false);

// Runs every load job (files of media, meshes, environment images) in parallel; the first error in the file's
// order is thrown.
void load_all(const std::vector<std::function<void()>>& jobs);

template <class T>
void add_load_job(Deferred<T>& d, std::vector<std::function<void()>>& jobs) {
  if (d.needs_load()) jobs.emplace_back([&d] { d.load(); });
}

// Load: the files every model needs, all at once (scene_load_files.cpp).
void load_files(SceneDesc& d);

// The shapes, materials, media and lights of each glTF file, after load_files (scene_gltf_expand.cpp).
void expand_gltf(SceneDesc& d);

// The camera of a glTF file rendered directly: the file's first perspective camera, or one that frames the
// meshes' bounds from a three-quarter view (35° round from +z towards +x, 25° up), the bounding sphere filling
// the vertical field of view.
Camera gltf_direct_camera(const SceneDesc& d);

// Build: the scene's models, the shapes' area lights, the accelerator (scene_build.cpp).
std::unique_ptr<Scene> build_scene(SceneDesc& d, const JsonSource& src);

}  // namespace kozu::scene_load
