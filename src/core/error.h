// Errors that reach the user: every message names the file and, for scene input, the JSON path.
#pragma once

#include <stdexcept>
#include <string>

namespace kozu {

// A problem with user input. Formats as "FILE: /json/path: message" (path omitted when empty).
class InputError : public std::runtime_error {
 public:
  InputError(std::string file, std::string json_path, const std::string& message)
      : std::runtime_error(format(file, json_path, message)),
        file_(std::move(file)),
        json_path_(std::move(json_path)) {}

  const std::string& file() const { return file_; }
  const std::string& json_path() const { return json_path_; }

  // "file: path: message" (the path left out when empty): every message about input has this form.
  static std::string format(const std::string& file, const std::string& path, const std::string& message) {
    std::string s = file;
    if (!path.empty()) s += ": " + path;
    return s + ": " + message;
  }

 private:
  std::string file_, json_path_;
};

}  // namespace kozu
