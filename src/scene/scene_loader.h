// Loads a kozu JSON scene (docs/scene-format.md) into a built Scene.
//
// Three phases, as the style guide asks:
//  1. parse: every key of the file is read and validated, and every name resolved, by the registries of each
//     kind (core/registry.h); no file other than the scene is opened, so every error in the scene itself is
//     found before any heavy I/O;
//  2. load: the files the models need (voxel grids, mesh files, environment images, image textures) are read in parallel
//     (TBB), each by the job its parser returned;
//  3. build: the scene's materials, media, shapes with their area lights, lights, and the Embree scene.
// The phases live in their own files: scene_parse.cpp (1), scene_load_files.cpp (2), scene_gltf_expand.cpp (a glTF
// shape's file turned into shapes, materials and lights after loading) and scene_build.cpp (3), on the descriptions of
// scene_desc.h; scene_loader.cpp gathers the included files and runs them in order.
// Any problem throws InputError naming the file and the JSON path (the first in the file's order when
// several files fail to load); nothing is half-built.
#pragma once

#include "scene/scene.h"
#include "scene/scene_overrides.h"

#include <filesystem>
#include <memory>
#include <string_view>

namespace kozu {

struct SceneLoadOptions {
  TextureCacheOptions textures;  // the texture cache's memory bound and conversion folder
  std::vector<SceneOverride> overrides;  // -D PATH=VALUE, set in a JSON scene before it is read (not glTF)
};

std::unique_ptr<Scene> load_scene_file(const std::filesystem::path& file, const SceneLoadOptions& options = {});
// display_name is used in messages; relative paths resolve against base_dir.
std::unique_ptr<Scene> load_scene_text(std::string_view json, const std::string& display_name,
                                       const std::filesystem::path& base_dir, const SceneLoadOptions& options = {});

// A glTF file (.gltf, .glb) rendered as a scene of its own (kozu render model.glb): its meshes, materials and
// lights, its first perspective camera (else one framing its bounds from a three-quarter view), and a uniform
// environment of radiance 1 when it has no lights.
std::unique_ptr<Scene> load_gltf_file(const std::filesystem::path& file, const SceneLoadOptions& options = {});

// The built-in demo scene (scenes/demo.json, compiled in).
std::unique_ptr<Scene> load_demo_scene(const SceneLoadOptions& options = {});
std::string_view demo_scene_json();

}  // namespace kozu
