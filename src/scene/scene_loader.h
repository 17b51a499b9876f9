// Loads a kozu JSON scene (docs/scene-format.md) into a built Scene.
//
// Three phases, as the style guide asks: parse the JSON into plain descriptions (validating every
// value, with its JSON path), load heavy resources (mesh files in parallel, environment images),
// then build (shapes, lights, Embree scene). Any problem throws InputError naming the file and
// the JSON path; nothing is half-built.
#pragma once

#include "scene/scene.h"

#include <filesystem>
#include <memory>
#include <string_view>

namespace kozu {

std::unique_ptr<Scene> load_scene_file(const std::filesystem::path& file);
// display_name is used in messages; relative paths resolve against base_dir.
std::unique_ptr<Scene> load_scene_text(std::string_view json, const std::string& display_name,
                                       const std::filesystem::path& base_dir);

// The built-in demo scene (scenes/demo.json, compiled in).
std::unique_ptr<Scene> load_demo_scene();
std::string_view demo_scene_json();

}  // namespace kozu
