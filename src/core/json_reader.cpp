#include "core/json_reader.h"

#include "core/json_path_walker.h"

#include <fmt/format.h>

#include <cerrno>
#include <cstdlib>
#include <iterator>
#include <new>

namespace kozu {

namespace {

std::string type_name(const Json& v) {
  switch (v.type()) {
    case Json::value_t::null:
      return "null";
    case Json::value_t::boolean:
      return "a boolean";
    case Json::value_t::string:
      return "the string " + json_excerpt(v);
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

// Integers in full up to ten digits (2147483647), larger magnitudes in short form (1e+15).
std::string format_number(double x) {
  if (std::abs(x) >= 1e10) return fmt::format("{:g}", x);
  return fmt::format("{}", x);
}

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

}  // namespace

std::string closest_match(std::string_view word, const std::vector<std::string>& candidates) {
  std::string best;
  size_t best_d = 3;  // suggest only close matches
  for (const auto& c : candidates) {
    const size_t d = edit_distance(word, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  return best;
}

namespace {

// Walks the text as SAX events (core/json_path_walker.h) and stops at the first problem the DOM parser would not
// report (nesting deeper than kMaxJsonDepth, a key given twice) or at a syntax error, so every message can name its
// JSON path.
class JsonChecker : public JsonPathWalker {
 public:
  bool start_object(std::size_t) {
    if (!start_container(true)) return false;
    keys_.emplace_back();
    return true;
  }
  bool key(string_t& k) {
    JsonPathWalker::key(k);
    if (!keys_.back().insert(k).second)
      return stop(fmt::format("key '{}' appears twice in this object", text_excerpt(k)));
    return true;
  }
  bool end_object() {
    keys_.pop_back();
    return end_container();
  }

 private:
  std::vector<std::set<std::string, std::less<>>> keys_;  // of each open object
};

// "line L, column C" of a byte offset (nlohmann's offsets count the failing character, so it is one past).
std::string line_and_column(std::string_view text, size_t byte) {
  size_t line = 1, col = 1;
  const size_t end = std::min<size_t>(byte == 0 ? 0 : byte - 1, text.size());
  for (size_t i = 0; i < end; ++i) {
    if (text[i] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
  return fmt::format("line {}, column {}", line, col);
}

// The JSON text of v for a message. A string that is not valid UTF-8 (a -D value or a flag from the command line)
// made dump() throw its own text ("[json.exception.type_error.316] invalid UTF-8 byte"): such bytes become U+FFFD.
std::string dump_for_message(const Json& v) { return v.dump(-1, ' ', false, Json::error_handler_t::replace); }

void append_excerpt(const Json& v, std::string& out, size_t budget) {
  if (out.size() >= budget) return;
  if (v.is_array() || v.is_object()) {
    out += v.is_array() ? '[' : '{';
    bool first = true;
    for (auto it = v.begin(); it != v.end(); ++it) {
      if (out.size() >= budget) {
        out += ", ...";
        break;
      }
      if (!first) out += ", ";
      first = false;
      if (v.is_object()) out += dump_for_message(Json(it.key())) + ": ";
      append_excerpt(*it, out, budget);
    }
    out += v.is_array() ? ']' : '}';
    return;
  }
  out += dump_for_message(v);
}

}  // namespace

std::string text_excerpt(std::string_view text, size_t max_chars) {
  if (text.size() <= max_chars) return std::string(text);
  // Cut at a UTF-8 character boundary.
  size_t n = max_chars;
  while (n > 0 && (static_cast<unsigned char>(text[n]) & 0xc0u) == 0x80u) --n;
  return std::string(text.substr(0, n)) + "...";
}

std::string json_excerpt(const Json& v, size_t max_chars) {
  if (v.is_string()) return dump_for_message(Json(text_excerpt(v.get_ref<const std::string&>(), max_chars)));
  std::string out;
  append_excerpt(v, out, max_chars);
  return text_excerpt(out, max_chars + 8);
}

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

namespace {

// Frees a document's values from the innermost out, leaving j an empty container or a scalar, without allocating
// (nlohmann's destructor allocates a stack of the largest array's size, which fails when memory has run out).
// Recursive: parse_json_text's documents are at most kMaxJsonDepth deep.
void dismantle(Json& j) noexcept {
  if (j.is_array()) {
    auto& a = j.get_ref<Json::array_t&>();
    while (!a.empty()) {
      dismantle(a.back());
      a.pop_back();
    }
  } else if (j.is_object()) {
    auto& o = j.get_ref<Json::object_t&>();
    while (!o.empty()) {
      const auto last = std::prev(o.end());
      dismantle(last->second);
      o.erase(last);
    }
  }
}

Json parse_checked_json_text(std::string_view text, const std::string& display_name) {
  JsonChecker checker;
  Json::sax_parse(text.begin(), text.end(), &checker, nlohmann::detail::input_format_t::json, /*strict=*/true,
                  /*ignore_comments=*/false);
  if (checker.syntax_error()) {
    std::string what = checker.parser_message();
    // A number too large for a double (e.g. 1e999): nlohmann reports "number overflow parsing '1e999'".
    if (what.find("number overflow") != std::string::npos) {
      const auto q0 = what.find('\''), q1 = what.rfind('\'');
      const std::string literal = q0 != std::string::npos && q1 > q0 ? what.substr(q0 + 1, q1 - q0 - 1) : "";
      throw InputError(display_name, checker.path(), fmt::format("number {} is out of range", text_excerpt(literal)));
    }
    // nlohmann prefixes "[json.exception.parse_error.101] parse error at line L, column C: "
    if (const auto p = what.find("syntax error"); p != std::string::npos) what = what.substr(p);
    throw InputError(
        display_name, "",
        fmt::format("{}: invalid JSON: {}", line_and_column(text, checker.error_byte()), text_excerpt(what, 200)));
  }
  if (checker.failed()) throw InputError(display_name, checker.path(), checker.message());
  // A parsed document takes several times its text's size, so a large file under a memory limit (ulimit -v, an
  // RLIMIT_AS) can run out here, before any estimate of the scene's memory can be made. nlohmann frees a document
  // with a stack as large as its largest array, allocated in its destructor: a partial document destroyed while an
  // out-of-memory error unwound ended the process (std::terminate). So the document is built in this frame and, on
  // that error, taken apart without allocating before the message is made.
  Json document;
  try {
    nlohmann::detail::json_sax_dom_parser<Json> builder(document, /*allow_exceptions_=*/true);
    Json::sax_parse(text.begin(), text.end(), &builder, nlohmann::detail::input_format_t::json, /*strict=*/true,
                    /*ignore_comments=*/false);
  } catch (const std::bad_alloc&) {
    dismantle(document);
    document = nullptr;
    throw InputError(display_name, "",
                     fmt::format("out of memory while reading the scene ({:.3g} MB)", double(text.size()) / 1e6));
  }
  return document;
}

}  // namespace

Json parse_json_text(std::string_view text, const std::string& display_name) {
  try {
    return parse_checked_json_text(text, display_name);
  } catch (const std::bad_alloc&) {
    // The check of the text (its keys) ran out: nothing large is left to free.
    throw InputError(display_name, "",
                     fmt::format("out of memory while reading the scene ({:.3g} MB)", double(text.size()) / 1e6));
  }
}

double json_to_double(const Json& v, const std::string& path, const JsonSource& src, const Range& range) {
  const std::string want = range.describe().empty() ? "a number" : "a number " + range.describe();
  if (!v.is_number()) throw InputError(src.display_name, path, fmt::format("expected {}, got {}", want, type_name(v)));
  const double x = v.get<double>();
  if (!std::isfinite(x))  // (json_excerpt would write an infinity as null: a flag's 1e999 becomes inf)
    throw InputError(src.display_name, path,
                     fmt::format("expected a finite number, got {}", std::isnan(x) ? "nan"
                                                                     : x > 0       ? "inf"
                                                                                   : "-inf"));
  if (!range.contains(x))
    throw InputError(src.display_name, path, fmt::format("expected {}, got {}", want, json_excerpt(v)));
  return x;
}

float json_to_float(const Json& v, const std::string& path, const JsonSource& src, const Range& range) {
  const double x = json_to_double(v, path, src, range);
  if (!std::isfinite(static_cast<float>(x)))
    throw InputError(src.display_name, path,
                     fmt::format("expected a number of magnitude below 3.4e38, got {}", json_excerpt(v)));
  return static_cast<float>(x);
}

int64_t json_to_integer(const Json& v, const std::string& path, const JsonSource& src, const Range& range) {
  const std::string want = range.describe().empty() ? "an integer" : "an integer " + range.describe();
  const auto fail = [&] {
    throw InputError(src.display_name, path,
                     fmt::format("expected {}, got {}", want, v.is_number() ? json_excerpt(v) : type_name(v)));
  };
  if (!v.is_number()) fail();
  const double x = v.get<double>();
  // |x| < 2^53 keeps the integral test exact; ranges are narrower still.
  if (!std::isfinite(x) || std::abs(x) >= 9007199254740992.0 || x != std::floor(x) || !range.contains(x)) fail();
  return v.is_number_float() ? static_cast<int64_t>(x) : v.get<int64_t>();
}

uint64_t json_to_uint64(const Json& v, const std::string& path, const JsonSource& src) {
  const auto fail = [&] {
    throw InputError(src.display_name, path,
                     fmt::format("expected an integer in [0, 18446744073709551615], got {}",
                                 v.is_number() ? json_excerpt(v) : type_name(v)));
  };
  if (v.is_number_unsigned()) return v.get<uint64_t>();
  if (v.is_number_integer()) {
    if (v.get<int64_t>() < 0) fail();
    return static_cast<uint64_t>(v.get<int64_t>());
  }
  if (!v.is_number_float()) fail();
  const double x = v.get<double>();
  if (!std::isfinite(x) || x < 0.0 || x >= 18446744073709551616.0 || x != std::floor(x)) fail();
  return static_cast<uint64_t>(x);
}

Json flag_value(std::string_view text) {
  if (text == "true") return true;
  if (text == "false") return false;
  // A decimal number: [-+]digits[.digits][e[-+]digits], at least one digit before or after the point.
  size_t i = 0;
  const auto digits = [&] {
    const size_t start = i;
    while (i < text.size() && text[i] >= '0' && text[i] <= '9') ++i;
    return i - start;
  };
  if (i < text.size() && (text[i] == '-' || text[i] == '+')) ++i;
  size_t mantissa = digits();
  bool integral = true;
  if (i < text.size() && text[i] == '.') {
    ++i;
    mantissa += digits();
    integral = false;
  }
  bool valid = mantissa > 0;
  if (valid && i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
    ++i;
    if (i < text.size() && (text[i] == '-' || text[i] == '+')) ++i;
    valid = digits() > 0;
    integral = false;
  }
  if (!valid || i != text.size()) return Json(std::string(text));
  const std::string s(text[0] == '+' ? text.substr(1) : text);
  if (integral) {
    // Leading zeros are decimal: strip them rather than let any parser read octal.
    const bool negative = s[0] == '-';
    const size_t first = s.find_first_not_of('0', negative ? 1 : 0);
    const std::string magnitude = first == std::string::npos ? "0" : s.substr(first);
    if (magnitude.size() <= 18) {
      const int64_t m = std::stoll(magnitude);
      return negative ? Json(-m) : Json(m);
    }
    if (!negative && magnitude.size() <= 20) {
      errno = 0;
      char* end = nullptr;
      const unsigned long long u = std::strtoull(magnitude.c_str(), &end, 10);
      if (errno == 0 && *end == '\0') return Json(static_cast<uint64_t>(u));
    }
  }
  // strtod on a checked decimal text: no hex, inf or nan can reach it. Out of range gives ±inf or 0, which
  // the number rules reject or accept as they would in a scene.
  return Json(std::strtod(s.c_str(), nullptr));
}

int64_t integer_flag_value(std::string_view text, const std::string& command, const std::string& flag,
                           const Range& range) {
  return json_to_integer(flag_value(text), flag, JsonSource{command, "."}, range);
}

uint64_t uint64_flag_value(std::string_view text, const std::string& command, const std::string& flag) {
  return json_to_uint64(flag_value(text), flag, JsonSource{command, "."});
}

double number_flag_value(std::string_view text, const std::string& command, const std::string& flag,
                         const Range& range) {
  return json_to_double(flag_value(text), flag, JsonSource{command, "."}, range);
}

std::string choice_flag_value(std::string_view text, const std::string& command, const std::string& flag,
                              const std::vector<std::string>& choices) {
  for (const std::string& c : choices)
    if (c == text) return c;
  std::string list;
  for (size_t i = 0; i < choices.size(); ++i) list += (i ? ", " : "") + choices[i];
  const std::string best = closest_match(text, choices);
  throw InputError(command, flag,
                   fmt::format("expected one of {}, got '{}'{}", list, text_excerpt(text),
                               best.empty() ? "" : fmt::format(" (did you mean '{}'?)", best)));
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

void JsonObject::warn(std::string_view key, const std::string& message) const {
  source_->warnings.push_back(InputError::format(source_->display_name, path_of(key), message));
}

void JsonObject::fail(std::string_view key, const std::string& message) const {
  throw InputError(source_->display_name, path_of(key), message);
}

void JsonObject::fail(const std::string& message) const { throw InputError(source_->display_name, path_, message); }

float JsonObject::get_float(std::string_view key, std::optional<float> def, const Range& range) const {
  if (def && !has(key)) return *def;
  return json_to_float(at(key), path_of(key), *source_, range);
}

double JsonObject::get_double(std::string_view key, std::optional<double> def, const Range& range) const {
  if (def && !has(key)) return *def;
  return json_to_double(at(key), path_of(key), *source_, range);
}

int JsonObject::get_int(std::string_view key, std::optional<int> def, const Range& range) const {
  if (def && !has(key)) return *def;
  const Range bounded{std::max(range.lo, -2147483648.0), std::min(range.hi, 2147483647.0), range.lo_open,
                      range.hi_open};
  return static_cast<int>(json_to_integer(at(key), path_of(key), *source_, bounded));
}

uint64_t JsonObject::get_uint64(std::string_view key, std::optional<uint64_t> def) const {
  if (def && !has(key)) return *def;
  return json_to_uint64(at(key), path_of(key), *source_);
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
  fail(key, fmt::format("unknown value '{}' (expected one of {})", text_excerpt(s), list));
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
  p = p.lexically_normal();
  source_->files.push_back(p);
  return p;
}

JsonObject JsonObject::get_object(std::string_view key) const { return JsonObject(at(key), path_of(key), source_); }

JsonArray JsonObject::get_array(std::string_view key) const { return JsonArray(at(key), path_of(key), source_); }

namespace {

// "comment" is allowed in every object, with any value, and read by nobody.
bool is_comment(const Json::const_iterator& it) { return it.key() == "comment"; }

}  // namespace

std::vector<std::string> JsonObject::keys() const {
  std::vector<std::string> out;
  for (auto it = j_->begin(); it != j_->end(); ++it)
    if (!is_comment(it)) out.push_back(it.key());
  return out;
}

void JsonObject::finish(const std::vector<std::string>& known_keys) const {
  for (auto it = j_->begin(); it != j_->end(); ++it) {
    if (read_.count(it.key()) || is_comment(it)) continue;
    std::vector<std::string> candidates = known_keys;
    for (const auto& k : known_) candidates.push_back(k);
    // A key this object knows but did not read here applies only in another configuration; its reader
    // should have said which (this is the fallback).
    if (std::find(candidates.begin(), candidates.end(), it.key()) != candidates.end())
      throw InputError(source_->display_name, path_of(it.key()),
                       fmt::format("key '{}' does not apply here", text_excerpt(it.key())));
    const std::string best = closest_match(it.key(), candidates);
    std::string msg = fmt::format("unknown key '{}'", text_excerpt(it.key()));
    if (!best.empty()) msg += fmt::format(" (did you mean '{}'?)", best);
    throw InputError(source_->display_name, path_of(it.key()), msg);
  }
}

JsonArray::JsonArray(const Json& j, std::string path, std::shared_ptr<const JsonSource> source)
    : j_(&j), path_(std::move(path)), source_(std::move(source)) {
  if (!j.is_array())
    throw InputError(source_->display_name, path_, fmt::format("expected an array, got {}", type_name(j)));
}

namespace {

// Element i of an array, or an error naming the array and its length: nlohmann's operator[] is unchecked on a
// const array and at() would throw its own text ("[json.exception.out_of_range.401] ..."), and neither may reach
// the user. Every reader checks the length first; this keeps a missed check a message, not a crash.
const Json& element(const Json& a, size_t i, const std::string& path, const JsonSource& src) {
  if (i >= a.size())
    throw InputError(src.display_name, path,
                     fmt::format("expected an array of at least {} elements, got {}", i + 1, a.size()));
  return a[i];
}

}  // namespace

JsonObject JsonArray::object(size_t i) const {
  return JsonObject(element(*j_, i, path_, *source_), path_of(i), source_);
}

float JsonArray::number(size_t i, const Range& range) const {
  return json_to_float(element(*j_, i, path_, *source_), path_of(i), *source_, range);
}

int64_t JsonArray::integer(size_t i, const Range& range) const {
  return json_to_integer(element(*j_, i, path_, *source_), path_of(i), *source_, range);
}

Vec3 JsonArray::vec3(size_t i) const { return json_to_vec3(element(*j_, i, path_, *source_), path_of(i), *source_); }

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
      sv = Vec3(json_to_float(s, t.path_of("scale"), t.source(), Range()));  // one rule with the vector: nonzero
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
