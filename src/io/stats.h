// The --stats JSON report and process memory figures.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>

namespace kozu {

// Peak resident set size of this process so far, in bytes (getrusage).
size_t peak_rss_bytes();

// Writes json (pretty-printed) through a temporary file and rename.
void write_json_file(const std::filesystem::path& file, const nlohmann::json& json);

}  // namespace kozu
