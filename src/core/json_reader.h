// Typed, path-aware access to a JSON scene description.
//
// Every value is read through a JsonObject that knows its JSON pointer (RFC 6901) and the file
// it came from, so each error names both: "scene.json: /materials/gold/ior: expected a number > 0".
// Keys are marked as they are read; finish() rejects any key nobody read (a misspelling).
//
// Parsing rejects what a scene never needs and an attacker could use: nesting deeper than kMaxJsonDepth
// levels, and a key given twice in one object (JSON leaves its meaning open). Messages quote values as short
// excerpts, never a whole value.
//
// One rule for numbers, shared by scene keys and command-line flags (flag_value): an integer key takes any
// finite number with an integral value (4 and 4.0, not 4.5); values are checked against their Range.
#pragma once

#include "core/color.h"
#include "core/error.h"
#include "core/math.h"
#include "core/transform.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace kozu {

using Json = nlohmann::json;

// The file a description came from: its name for messages and its folder for relative paths.
struct JsonSource {
  std::string display_name;        // as the user wrote it (or "<demo>")
  std::filesystem::path base_dir;  // relative paths in the file resolve against this
  // Every file get_path resolved, in order: the render's inputs, which no output may overwrite.
  mutable std::vector<std::filesystem::path> files;
  // Warnings of the parse phase (JsonObject::warn), "file: /path: message", in the file's order.
  mutable std::vector<std::string> warnings;
};

// An inclusive or exclusive interval a number must lie in, with its description for messages.
struct Range {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false;
  bool hi_open = false;

  static Range positive() { return {0.0, std::numeric_limits<double>::infinity(), true, false}; }
  static Range non_negative() { return {0.0, std::numeric_limits<double>::infinity(), false, false}; }
  static Range unit() { return {0.0, 1.0, false, false}; }
  static Range closed(double a, double b) { return {a, b, false, false}; }
  static Range at_least(double a) { return {a, std::numeric_limits<double>::infinity(), false, false}; }

  bool contains(double x) const;
  std::string describe() const;  // "> 0", ">= 0", "in [0, 1]", "" when unconstrained
};

// The candidate closest to word by edit distance, if within 2 edits ("did you mean" suggestions); else "".
std::string closest_match(std::string_view word, const std::vector<std::string>& candidates);

// Deepest nesting of arrays and objects a scene file may have (a scene needs about 8).
inline constexpr int kMaxJsonDepth = 64;

// A short quotation of a value or a text for messages: at most about max_chars characters, cut with "...".
std::string json_excerpt(const Json& v, size_t max_chars = 40);
std::string text_excerpt(std::string_view text, size_t max_chars = 40);

std::string json_pointer_append(const std::string& path, std::string_view key);
std::string json_pointer_append(const std::string& path, size_t index);

class JsonArray;

class JsonObject {
 public:
  // Throws "expected an object" if j is not one.
  JsonObject(const Json& j, std::string path, std::shared_ptr<const JsonSource> source);

  bool has(std::string_view key) const;
  const std::string& path() const { return path_; }
  std::string path_of(std::string_view key) const { return json_pointer_append(path_, key); }
  const JsonSource& source() const { return *source_; }
  const std::shared_ptr<const JsonSource>& source_ptr() const { return source_; }

  // Typed getters. Without a default the key is required. Each marks the key as read.
  float get_float(std::string_view key, std::optional<float> def = {}, const Range& range = {}) const;
  double get_double(std::string_view key, std::optional<double> def = {}, const Range& range = {}) const;
  int get_int(std::string_view key, std::optional<int> def = {}, const Range& range = {}) const;
  uint64_t get_uint64(std::string_view key, std::optional<uint64_t> def = {}) const;
  bool get_bool(std::string_view key, std::optional<bool> def = {}) const;
  std::string get_string(std::string_view key, std::optional<std::string> def = {}) const;
  // One of `choices`; the message lists them.
  std::string get_enum(std::string_view key, const std::vector<std::string>& choices,
                       std::optional<std::string> def = {}) const;
  Vec3 get_vec3(std::string_view key, std::optional<Vec3> def = {}) const;
  // Nonzero vector (a direction or an axis).
  Vec3 get_direction(std::string_view key, std::optional<Vec3> def = {}) const;
  // [r, g, b] or a single number for grey; every component must satisfy range.
  Rgb get_rgb(std::string_view key, std::optional<Rgb> def = {}, const Range& range = Range::non_negative()) const;
  // Path relative to the scene file, resolved; the file itself is not opened here.
  std::filesystem::path get_path(std::string_view key) const;

  JsonObject get_object(std::string_view key) const;
  JsonArray get_array(std::string_view key) const;
  // The raw value (for keys that accept several shapes, e.g. a number or an array).
  const Json& raw(std::string_view key) const;
  // All keys in document order (for objects of user-named entries such as "materials"), but "comment".
  std::vector<std::string> keys() const;

  // Rejects keys that were never read, naming the first and suggesting the closest known key; "comment", with any
  // value, is allowed in every object (the scene file's way to annotate: JSON has no comments).
  void finish(const std::vector<std::string>& known_keys = {}) const;
  // Marks a key read without using it (keys reserved for tools, e.g. "comment").
  void ignore(std::string_view key) const;

  // A key that is valid but does nothing here (e.g. multiscatter on a smooth surface): a warning, not an error.
  void warn(std::string_view key, const std::string& message) const;
  [[noreturn]] void fail(std::string_view key, const std::string& message) const;
  [[noreturn]] void fail(const std::string& message) const;

 private:
  const Json& at(std::string_view key) const;  // marks read; throws if missing
  const Json* find(std::string_view key) const;
  // Records that a reader asked for key, present or not (for "did you mean" suggestions).
  void know(std::string_view key) const { known_.emplace(key); }

  const Json* j_;
  std::string path_;
  std::shared_ptr<const JsonSource> source_;
  mutable std::set<std::string, std::less<>> read_;
  mutable std::set<std::string, std::less<>> known_;
};

class JsonArray {
 public:
  JsonArray(const Json& j, std::string path, std::shared_ptr<const JsonSource> source);
  size_t size() const { return j_->size(); }
  std::string path_of(size_t i) const { return json_pointer_append(path_, i); }
  const std::string& path() const { return path_; }
  JsonObject object(size_t i) const;
  float number(size_t i, const Range& range = {}) const;
  int64_t integer(size_t i, const Range& range) const;
  Vec3 vec3(size_t i) const;
  const Json& raw(size_t i) const { return (*j_)[i]; }
  [[noreturn]] void fail(const std::string& message) const;
  [[noreturn]] void fail(size_t i, const std::string& message) const;

 private:
  const Json* j_;
  std::string path_;
  std::shared_ptr<const JsonSource> source_;
};

// Parses text as JSON; syntax errors name the line and column.
Json parse_json_text(std::string_view text, const std::string& display_name);

// The string at j[key], when j has one there (peeking at raw JSON, as a load-time step does before the key's parser
// reports what is wrong with it).
inline bool json_string(const Json& j, const char* key, std::string* value) {
  if (!j.is_object() || !j.contains(key) || !j[key].is_string()) return false;
  *value = j[key].get<std::string>();
  return true;
}

// Reads a numeric JSON value, rejecting non-numbers, non-finite values (for float: beyond float's range) and
// values outside range.
double json_to_double(const Json& v, const std::string& path, const JsonSource& src, const Range& range = {});
float json_to_float(const Json& v, const std::string& path, const JsonSource& src, const Range& range = {});
// Reads an integer: a finite number with an integral value inside range (which should be finite).
int64_t json_to_integer(const Json& v, const std::string& path, const JsonSource& src, const Range& range);
// Reads an integer in [0, 2^64).
uint64_t json_to_uint64(const Json& v, const std::string& path, const JsonSource& src);
// The JSON value a command-line text stands for, so that a flag is validated by the rule of its scene key:
// a decimal number (leading zeros are decimal: "010" is 10; no hex, octal, inf or nan), true/false, or else
// the text as a string (which a number rule then rejects, quoting it).
Json flag_value(std::string_view text);
// A flag of a command (other than render's settings, which have their scene keys' rules) read by the same rules:
// a bad value throws InputError(command, flag, ...), which prints as "kozu fit-ltc: --size: expected an integer in
// [2, 256], got 1" and, like every bad value, exits with status 1 (2 is for usage errors: an unknown option, a
// missing argument).
int64_t integer_flag_value(std::string_view text, const std::string& command, const std::string& flag,
                           const Range& range);
uint64_t uint64_flag_value(std::string_view text, const std::string& command, const std::string& flag);
double number_flag_value(std::string_view text, const std::string& command, const std::string& flag,
                         const Range& range = {});
// One of choices: "expected one of a, b, c, got 'x'".
std::string choice_flag_value(std::string_view text, const std::string& command, const std::string& flag,
                              const std::vector<std::string>& choices);
Vec3 json_to_vec3(const Json& v, const std::string& path, const JsonSource& src);
// A "transform" object (docs/scene-format.md): a row-major affine "matrix", or "scale", "rotate" and
// "translate" applied in that order.
Transform read_transform(const JsonObject& t);

}  // namespace kozu
