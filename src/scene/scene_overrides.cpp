#include "scene/scene_overrides.h"

#include <fmt/format.h>

#include <stdexcept>

namespace kozu {

namespace {

// The whole argument must be one JSON value (no trailing text, no duplicate keys, bounded depth: the scene
// file's own rules); anything else is a string, so -D /materials/m/type=conductor needs no quotes. What starts
// like an array, an object or a quoted string must be one.
Json override_value(const std::string& argument, const std::string& text) {
  if (text.empty()) return Json(text);
  try {
    return parse_json_text(text, "-D");
  } catch (const InputError& e) {
    if (text[0] == '[' || text[0] == '{' || text[0] == '"')
      throw std::invalid_argument(fmt::format("-D '{}': the value is not valid JSON: {}", argument,
                                              std::string(e.what()).substr(4)));  // after "-D: "
    return Json(text);
  }
}

}  // namespace

SceneOverride parse_scene_override(const std::string& argument) {
  const auto eq = argument.find('=');
  if (eq == std::string::npos || eq == 0 || argument[0] != '/')
    throw std::invalid_argument(fmt::format(
        "-D '{}': expected PATH=VALUE with PATH a JSON path from the scene's root, e.g. -D /camera/fov=30", argument));
  SceneOverride o;
  o.path = argument.substr(0, eq);
  o.text = argument;
  try {
    (void)Json::json_pointer(o.path);
  } catch (const Json::exception&) {
    throw std::invalid_argument(
        fmt::format("-D '{}': '{}' is not a JSON path ('~' must be written ~0 and '/' in a key ~1)", argument, o.path));
  }
  o.value = override_value(argument, argument.substr(eq + 1));
  return o;
}

void apply_scene_overrides(Json& root, const std::vector<SceneOverride>& overrides, const std::string& display_name) {
  for (const SceneOverride& o : overrides) {
    const Json::json_pointer pointer(o.path);
    const Json::json_pointer parent = pointer.parent_pointer();
    const std::string key = pointer.back();
    const auto fail = [&](const std::string& path, const std::string& why) {
      throw InputError(display_name, path, why);
    };
    // contains() throws its own text ("[json.exception.out_of_range.404] ...") for an index beyond size_t.
    const auto present = [&] {
      try {
        return root.contains(parent);
      } catch (const Json::exception&) {
        return false;
      }
    };
    if (!present()) fail(parent.to_string(), "no such object or array in the scene");
    Json& holder = root.at(parent);
    if (holder.is_object()) {
      if (o.value.is_null())
        holder.erase(key);  // null removes the key, as in JSON Merge Patch (RFC 7386)
      else
        holder[key] = o.value;
    } else if (holder.is_array()) {
      if (key == "-") {
        holder.push_back(o.value);
        continue;
      }
      size_t index = 0;
      const bool digits = !key.empty() && key.size() <= 9 && key.find_first_not_of("0123456789") == std::string::npos &&
                          (key.size() == 1 || key[0] != '0');
      if (digits) index = std::stoul(key);
      if (!digits || index >= holder.size())
        fail(parent.to_string(),
             fmt::format("an array of {} elements has no element '{}' (an index, or - to append)", holder.size(), key));
      if (o.value.is_null())
        holder.erase(index);
      else
        holder[index] = o.value;
    } else {
      fail(parent.to_string(), fmt::format("is a {}, not an object or array", holder.type_name()));
    }
  }
}

std::string override_note(const std::vector<SceneOverride>& overrides, const std::string& json_path) {
  const auto under = [&](const std::string& prefix) {
    return json_path.compare(0, prefix.size(), prefix) == 0 &&
           (json_path.size() == prefix.size() || json_path[prefix.size()] == '/');
  };
  // The override that set the key itself (or an object holding it); else one beside it, a "type" first (a new type
  // makes the object's other keys unknown); the last one given wins a tie.
  for (int pass = 0; pass < 3; ++pass)
    for (auto o = overrides.rbegin(); o != overrides.rend(); ++o) {
      const Json::json_pointer pointer(o->path);
      const std::string parent = pointer.parent_pointer().to_string();
      const bool hit = pass == 0   ? under(o->path)
                       : pass == 1 ? !parent.empty() && under(parent) && pointer.back() == "type"
                                   : !parent.empty() && under(parent);
      if (hit) return fmt::format(" (set by -D {})", o->text);
    }
  return {};
}

}  // namespace kozu
