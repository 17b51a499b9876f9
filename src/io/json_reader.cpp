#include "io/json_reader.h"

#include <fmt/format.h>

namespace kozu {

namespace {

std::string type_name(const Json& v) {
  switch (v.type()) {
    case Json::value_t::null:
      return "null";
    case Json::value_t::boolean:
      return "a boolean";
    case Json::value_t::string:
      return "a string";
    case Json::value_t::array:
      return "an array";
    case Json::value_t::object:
      return "an object";
    case Json::value_t::number_integer:
    case Json::value_t::number_unsigned:
    case Json::value_t::number_float:
      return "a number";
    default:
      return "an unsupported value";
  }
}

std::string format_number(double x) { return fmt::format("{}", x); }

// Levenshtein distance for "did you mean" suggestions.
size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

// Tracks the JSON pointer of the value being parsed, for errors nlohmann reports without one.
class PathTracker {
 public:
  using number_integer_t = Json::number_integer_t;
  using number_unsigned_t = Json::number_unsigned_t;
  using number_float_t = Json::number_float_t;
  using string_t = Json::string_t;
  using binary_t = Json::binary_t;

  bool null() { return value(); }
  bool boolean(bool) { return value(); }
  bool number_integer(number_integer_t) { return value(); }
  bool number_unsigned(number_unsigned_t) { return value(); }
  bool number_float(number_float_t, const string_t&) { return value(); }
  bool string(string_t&) { return value(); }
  bool binary(binary_t&) { return value(); }
  bool start_object(std::size_t) {
    begin_value();
    stack_.push_back({true, "", 0, false});
    return true;
  }
  bool key(string_t& k) {
    stack_.back().key = k;
    return true;
  }
  bool end_object() { return end_container(); }
  bool start_array(std::size_t) {
    begin_value();
    stack_.push_back({false, "", 0, false});
    return true;
  }
  bool end_array() { return end_container(); }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) {
    // The failing value belongs to the innermost container at its current key or index.
    begin_value();
    path_ = pointer();
    return false;
  }
  const std::string& path() const { return path_; }

 private:
  struct Level {
    bool object;
    std::string key;
    size_t index;
    bool started;  // an array element has been begun at `index`
  };
  void begin_value() {
    if (!stack_.empty() && !stack_.back().object) {
      if (stack_.back().started) ++stack_.back().index;
      stack_.back().started = true;
    }
  }
  bool value() {
    begin_value();
    return true;
  }
  bool end_container() {
    stack_.pop_back();
    return true;
  }
  std::string pointer() const {
    std::string p;
    for (const Level& l : stack_) p = l.object ? json_pointer_append(p, l.key) : json_pointer_append(p, l.index);
    return p;
  }
  std::vector<Level> stack_;
  std::string path_;
};

std::string locate_parse_error(std::string_view text) {
  PathTracker tracker;
  Json::sax_parse(text.begin(), text.end(), &tracker, nlohmann::detail::input_format_t::json, /*strict=*/true,
                  /*ignore_comments=*/false);
  return tracker.path();
}

}  // namespace

bool Range::contains(double x) const {
  if (lo_open ? !(x > lo) : !(x >= lo)) return false;
  if (hi_open ? !(x < hi) : !(x <= hi)) return false;
  return true;
}

std::string Range::describe() const {
  const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
  if (has_lo && has_hi)
    return fmt::format("in {}{}, {}{}", lo_open ? "(" : "[", format_number(lo), format_number(hi), hi_open ? ")" : "]");
  if (has_lo) return fmt::format("{} {}", lo_open ? ">" : ">=", format_number(lo));
  if (has_hi) return fmt::format("{} {}", hi_open ? "<" : "<=", format_number(hi));
  return "";
}

std::string json_pointer_append(const std::string& path, std::string_view key) {
  std::string out = path + "/";
  for (char c : key) {
    if (c == '~')
      out += "~0";
    else if (c == '/')
      out += "~1";
    else
      out += c;
  }
  return out;
}

std::string json_pointer_append(const std::string& path, size_t index) { return path + "/" + std::to_string(index); }

Json parse_json_text(std::string_view text, const std::string& display_name) {
  try {
    return Json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/true, /*ignore_comments=*/false);
  } catch (const Json::parse_error& e) {
    // Locate the byte offset as line:column for the message.
    size_t line = 1, col = 1;
    const size_t end = std::min<size_t>(e.byte == 0 ? 0 : e.byte - 1, text.size());
    for (size_t i = 0; i < end; ++i) {
      if (text[i] == '\n') {
        ++line;
        col = 1;
      } else {
        ++col;
      }
    }
    std::string what = e.what();
    // nlohmann prefixes "[json.exception.parse_error.101] parse error at line L, column C: "
    if (const auto p = what.find("syntax error"); p != std::string::npos) what = what.substr(p);
    throw InputError(display_name, "", fmt::format("line {}, column {}: invalid JSON: {}", line, col, what));
  } catch (const Json::out_of_range& e) {
    // A number too large for a double (e.g. 1e999). nlohmann reports no position, so the text is
    // parsed again with a handler that tracks the JSON path and stops at the same error.
    const std::string path = locate_parse_error(text);
    const std::string what = e.what();
    const auto q0 = what.find('\''), q1 = what.rfind('\'');
    const std::string literal = q0 != std::string::npos && q1 > q0 ? what.substr(q0 + 1, q1 - q0 - 1) : "";
    throw InputError(display_name, path, fmt::format("number {} is out of range", literal));
  }
}

float json_to_float(const Json& v, const std::string& path, const JsonSource& src, const Range& range) {
  const std::string want = range.describe().empty() ? "a number" : "a number " + range.describe();
  if (!v.is_number()) throw InputError(src.display_name, path, fmt::format("expected {}, got {}", want, type_name(v)));
  const double x = v.get<double>();
  if (!std::isfinite(x) || !std::isfinite(static_cast<float>(x)))
    throw InputError(src.display_name, path, fmt::format("expected a finite number, got {}", v.dump()));
  if (!range.contains(x)) throw InputError(src.display_name, path, fmt::format("expected {}, got {}", want, v.dump()));
  return static_cast<float>(x);
}

Vec3 json_to_vec3(const Json& v, const std::string& path, const JsonSource& src) {
  if (!v.is_array() || v.size() != 3)
    throw InputError(src.display_name, path,
                     fmt::format("expected an array of 3 numbers, got {}",
                                 v.is_array() ? fmt::format("an array of {}", v.size()) : type_name(v)));
  return Vec3(json_to_float(v[0], json_pointer_append(path, size_t{0}), src),
              json_to_float(v[1], json_pointer_append(path, size_t{1}), src),
              json_to_float(v[2], json_pointer_append(path, size_t{2}), src));
}

JsonObject::JsonObject(const Json& j, std::string path, std::shared_ptr<const JsonSource> source)
    : j_(&j), path_(std::move(path)), source_(std::move(source)) {
  if (!j.is_object())
    throw InputError(source_->display_name, path_, fmt::format("expected an object, got {}", type_name(j)));
}

const Json* JsonObject::find(std::string_view key) const {
  const auto it = j_->find(key);
  return it == j_->end() ? nullptr : &*it;
}

bool JsonObject::has(std::string_view key) const {
  know(key);
  return find(key) != nullptr;
}

const Json& JsonObject::at(std::string_view key) const {
  know(key);
  const Json* v = find(key);
  if (!v) throw InputError(source_->display_name, path_, fmt::format("missing required key '{}'", key));
  read_.emplace(key);
  return *v;
}

const Json& JsonObject::raw(std::string_view key) const { return at(key); }

void JsonObject::ignore(std::string_view key) const { read_.emplace(key); }

void JsonObject::fail(std::string_view key, const std::string& message) const {
  throw InputError(source_->display_name, path_of(key), message);
}

void JsonObject::fail(const std::string& message) const { throw InputError(source_->display_name, path_, message); }

float JsonObject::get_float(std::string_view key, std::optional<float> def, const Range& range) const {
  if (def && !has(key)) return *def;
  return json_to_float(at(key), path_of(key), *source_, range);
}

int JsonObject::get_int(std::string_view key, std::optional<int> def, const Range& range) const {
  if (def && !has(key)) return *def;
  const Json& v = at(key);
  const std::string want = range.describe().empty() ? "an integer" : "an integer " + range.describe();
  if (!v.is_number_integer()) {
    // Accept 4.0 but not 4.5.
    if (v.is_number_float() && std::isfinite(v.get<double>()) && v.get<double>() == std::floor(v.get<double>()) &&
        std::abs(v.get<double>()) < 2e9) {
    } else {
      fail(key, fmt::format("expected {}, got {}", want, v.is_number() ? v.dump() : type_name(v)));
    }
  }
  const double x = v.get<double>();
  if (!range.contains(x) || std::abs(x) > 2147483647.0) fail(key, fmt::format("expected {}, got {}", want, v.dump()));
  return static_cast<int>(x);
}

uint64_t JsonObject::get_uint64(std::string_view key, std::optional<uint64_t> def) const {
  if (def && !has(key)) return *def;
  const Json& v = at(key);
  if (!v.is_number_unsigned() && !(v.is_number_integer() && v.get<int64_t>() >= 0))
    fail(key, fmt::format("expected an integer >= 0, got {}", v.is_number() ? v.dump() : type_name(v)));
  return v.get<uint64_t>();
}

bool JsonObject::get_bool(std::string_view key, std::optional<bool> def) const {
  if (def && !has(key)) return *def;
  const Json& v = at(key);
  if (!v.is_boolean()) fail(key, fmt::format("expected true or false, got {}", type_name(v)));
  return v.get<bool>();
}

std::string JsonObject::get_string(std::string_view key, std::optional<std::string> def) const {
  if (def && !has(key)) return *def;
  const Json& v = at(key);
  if (!v.is_string()) fail(key, fmt::format("expected a string, got {}", type_name(v)));
  return v.get<std::string>();
}

std::string JsonObject::get_enum(std::string_view key, const std::vector<std::string>& choices,
                                 std::optional<std::string> def) const {
  const std::string s = get_string(key, def);
  for (const auto& c : choices)
    if (c == s) return s;
  std::string list;
  for (size_t i = 0; i < choices.size(); ++i) list += (i ? ", '" : "'") + choices[i] + "'";
  fail(key, fmt::format("unknown value '{}' (expected one of {})", s, list));
}

Vec3 JsonObject::get_vec3(std::string_view key, std::optional<Vec3> def) const {
  if (def && !has(key)) return *def;
  return json_to_vec3(at(key), path_of(key), *source_);
}

Vec3 JsonObject::get_direction(std::string_view key, std::optional<Vec3> def) const {
  const Vec3 v = get_vec3(key, def);
  if (!(glm::dot(v, v) > 0.0f)) fail(key, "expected a nonzero vector");
  return v;
}

Rgb JsonObject::get_rgb(std::string_view key, std::optional<Rgb> def, const Range& range) const {
  if (def && !has(key)) return *def;
  const Json& v = at(key);
  const std::string p = path_of(key);
  if (v.is_number()) {
    const float x = json_to_float(v, p, *source_, range);
    return Rgb(x);
  }
  if (!v.is_array() || v.size() != 3)
    fail(key, fmt::format("expected [r, g, b] or a number, got {}",
                          v.is_array() ? fmt::format("an array of {}", v.size()) : type_name(v)));
  return Rgb(json_to_float(v[0], json_pointer_append(p, size_t{0}), *source_, range),
             json_to_float(v[1], json_pointer_append(p, size_t{1}), *source_, range),
             json_to_float(v[2], json_pointer_append(p, size_t{2}), *source_, range));
}

std::filesystem::path JsonObject::get_path(std::string_view key) const {
  const std::string s = get_string(key);
  if (s.empty()) fail(key, "expected a file name, got an empty string");
  std::filesystem::path p(s);
  if (p.is_relative()) p = source_->base_dir / p;
  return p.lexically_normal();
}

JsonObject JsonObject::get_object(std::string_view key) const { return JsonObject(at(key), path_of(key), source_); }

JsonArray JsonObject::get_array(std::string_view key) const { return JsonArray(at(key), path_of(key), source_); }

std::vector<std::string> JsonObject::keys() const {
  std::vector<std::string> out;
  for (auto it = j_->begin(); it != j_->end(); ++it) out.push_back(it.key());
  return out;
}

void JsonObject::finish(const std::vector<std::string>& known_keys) const {
  for (auto it = j_->begin(); it != j_->end(); ++it) {
    if (read_.count(it.key())) continue;
    std::vector<std::string> candidates = known_keys;
    for (const auto& k : known_) candidates.push_back(k);
    std::string best;
    size_t best_d = 3;  // suggest only close matches
    for (const auto& c : candidates) {
      const size_t d = edit_distance(it.key(), c);
      if (d < best_d) {
        best_d = d;
        best = c;
      }
    }
    std::string msg = fmt::format("unknown key '{}'", it.key());
    if (!best.empty()) msg += fmt::format(" (did you mean '{}'?)", best);
    throw InputError(source_->display_name, path_of(it.key()), msg);
  }
}

JsonArray::JsonArray(const Json& j, std::string path, std::shared_ptr<const JsonSource> source)
    : j_(&j), path_(std::move(path)), source_(std::move(source)) {
  if (!j.is_array())
    throw InputError(source_->display_name, path_, fmt::format("expected an array, got {}", type_name(j)));
}

JsonObject JsonArray::object(size_t i) const { return JsonObject((*j_)[i], path_of(i), source_); }

float JsonArray::number(size_t i, const Range& range) const {
  return json_to_float((*j_)[i], path_of(i), *source_, range);
}

Vec3 JsonArray::vec3(size_t i) const { return json_to_vec3((*j_)[i], path_of(i), *source_); }

void JsonArray::fail(const std::string& message) const { throw InputError(source_->display_name, path_, message); }

void JsonArray::fail(size_t i, const std::string& message) const {
  throw InputError(source_->display_name, path_of(i), message);
}

Transform read_transform(const JsonObject& t) {
  if (t.has("matrix")) {
    const JsonArray rows = t.get_array("matrix");
    if (rows.size() != 4) rows.fail("expected 4 rows of 4 numbers (row-major)");
    Mat4 m(1.0f);
    for (size_t r = 0; r < 4; ++r) {
      const JsonArray row(rows.raw(r), rows.path_of(r), t.source_ptr());
      if (row.size() != 4) row.fail("expected 4 numbers");
      for (size_t c = 0; c < 4; ++c) m[c][r] = row.number(c);  // glm is column-major
    }
    if (t.has("translate") || t.has("rotate") || t.has("scale"))
      t.fail("matrix", "give either 'matrix' or 'translate'/'rotate'/'scale', not both");
    if (std::abs(glm::determinant(Mat3(m))) < 1e-12f) t.fail("matrix", "matrix is singular");
    if (m[0][3] != 0.0f || m[1][3] != 0.0f || m[2][3] != 0.0f || m[3][3] != 1.0f)
      t.fail("matrix", "expected an affine matrix (last row [0, 0, 0, 1])");
    t.finish();
    return Transform(m);
  }
  Transform result;
  // Applied as scale, then rotate, then translate.
  if (t.has("scale")) {
    const Json& s = t.raw("scale");
    Vec3 sv;
    if (s.is_number())
      sv = Vec3(json_to_float(s, t.path_of("scale"), t.source(), Range::positive()));
    else
      sv = t.get_vec3("scale");
    if (sv.x == 0.0f || sv.y == 0.0f || sv.z == 0.0f) t.fail("scale", "scale factors must be nonzero");
    result = Transform::scale(sv);
  }
  if (t.has("rotate")) {
    const JsonArray r = t.get_array("rotate");
    if (r.size() != 4) r.fail("expected [axis_x, axis_y, axis_z, degrees]");
    const Vec3 axis(r.number(0), r.number(1), r.number(2));
    if (!(glm::dot(axis, axis) > 0.0f)) r.fail("rotation axis must be nonzero");
    result = Transform::rotate(axis, r.number(3)) * result;
  }
  if (t.has("translate")) result = Transform::translate(t.get_vec3("translate")) * result;
  t.finish();
  return result;
}

}  // namespace kozu
