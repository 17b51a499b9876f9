// Command-line overrides of scene keys: `kozu render scene.json -D /camera/fov=30 -D /materials/gold/roughness=0.3`.
// Each sets one value, addressed by its JSON pointer (RFC 6901), in the parsed scene before the scene is read, so
// an override is validated exactly like the file: a misspelt key is an unknown key, a value out of range is named
// with its range, and the message names the JSON path.
#pragma once

#include "core/json_reader.h"

#include <string>
#include <vector>

namespace kozu {

struct SceneOverride {
  std::string path;  // a JSON pointer, "/camera/fov"
  Json value;        // the VALUE as JSON (30, [0, 1, 2], "gold"), or as a string when it is not JSON (gold)
  std::string text;  // the argument as given, PATH=VALUE, for messages
};

// Parses PATH=VALUE; throws std::invalid_argument with a message naming the argument.
SceneOverride parse_scene_override(const std::string& argument);

// Sets each override in root, in order. The object or array that holds the key must exist (a new key of an
// existing object is allowed: reading the scene then rejects it if it is unknown); an array element is replaced by
// its index, or appended with "-"; the value null removes the key or element (as in JSON Merge Patch). Throws
// InputError naming `display_name` and the path (override_note adds the argument).
void apply_scene_overrides(Json& root, const std::vector<SceneOverride>& overrides, const std::string& display_name);

// " (set by -D PATH=VALUE)" when an error at json_path may come from an override: the path lies under the key it
// set or, for a key of a nested object, beside it (a changed "type" makes the object's other keys unknown); else "".
std::string override_note(const std::vector<SceneOverride>& overrides, const std::string& json_path);

}  // namespace kozu
