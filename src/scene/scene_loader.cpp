#include "scene/scene_loader.h"

#include "core/error.h"
#include "core/file_io.h"
#include "core/json_reader.h"
#include "scene/scene_desc.h"
#include "textures/procedural_image.h"

#include <fmt/format.h>

#include <map>

namespace kozu {

extern const std::string_view kDemoSceneJson;

namespace {

using namespace scene_load;

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

void collect_includes(const JsonObject& file, SceneFiles& files, std::vector<std::filesystem::path>& chain,
                      const SceneLoadOptions& options) {
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
      expand_procedural_images(*files.json.back(), path.string(), TextureCache::convert_folder(options.textures));
      files.included.push_back(path);
      const JsonObject included(*files.json.back(), "", src);
      chain.push_back(key);
      collect_includes(included, files, chain, options);
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
  collect_includes(root, files, chain, options);
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
  expand_procedural_images(root, display_name, TextureCache::convert_folder(options.textures));
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
