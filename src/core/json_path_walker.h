// A SAX walk over JSON text (nlohmann::json::sax_parse) that knows the JSON pointer of the value being parsed and
// stops at nesting deeper than kMaxJsonDepth, so that checks made before a document is built (the scene parser's,
// the glTF importer's before tinygltf parses recursively) can name the path of what they refuse. Derived walkers
// hide the handlers they need (a key seen twice, a number out of range) and call stop() to end the walk.
#pragma once

#include "core/json_reader.h"

#include <fmt/format.h>

#include <string>
#include <utility>
#include <vector>

namespace kozu {

class JsonPathWalker {
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
  bool start_object(std::size_t) { return start_container(true); }
  bool key(string_t& k) {
    stack_.back().key = k;
    return true;
  }
  bool end_object() { return end_container(); }
  bool start_array(std::size_t) { return start_container(false); }
  bool end_array() { return end_container(); }
  // A syntax error: the failing value belongs to the innermost container at its current key or index.
  bool parse_error(std::size_t byte, const std::string&, const nlohmann::detail::exception& e) {
    begin_value();
    path_ = pointer();
    error_byte_ = byte;
    syntax_error_ = e.what();
    return false;
  }

  // Set when the walk stopped: the JSON path, and either a message of a check or the parser's exception text.
  bool failed() const { return !message_.empty() || !syntax_error_.empty(); }
  bool syntax_error() const { return !syntax_error_.empty(); }
  const std::string& path() const { return path_; }
  const std::string& message() const { return message_; }
  const std::string& parser_message() const { return syntax_error_; }
  size_t error_byte() const { return error_byte_; }

 protected:
  struct Level {
    bool object;
    std::string key;
    size_t index;
    bool started;  // an array element has been begun at `index`
  };
  // Counts an array's element before its value is handled, so pointer() names it.
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
  bool start_container(bool object) {
    begin_value();
    if (stack_.size() >= static_cast<size_t>(kMaxJsonDepth))
      return stop(fmt::format("arrays and objects nested deeper than {} levels", kMaxJsonDepth));
    stack_.push_back({object, "", 0, false});
    return true;
  }
  bool end_container() {
    stack_.pop_back();
    return true;
  }
  bool stop(std::string message) {
    path_ = pointer();
    message_ = std::move(message);
    return false;
  }
  std::string pointer() const {
    std::string p;
    for (const Level& l : stack_) p = l.object ? json_pointer_append(p, l.key) : json_pointer_append(p, l.index);
    return p;
  }
  const std::vector<Level>& stack() const { return stack_; }

 private:
  std::vector<Level> stack_;
  std::string path_, message_, syntax_error_;
  size_t error_byte_ = 0;
};

}  // namespace kozu
