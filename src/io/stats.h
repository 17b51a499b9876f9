// The --stats JSON report (process memory figures are in core/memory.h).
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>

namespace kozu {

// Writes json (pretty-printed) through a temporary file and rename.
void write_json_file(const std::filesystem::path& file, const nlohmann::json& json);

}  // namespace kozu
