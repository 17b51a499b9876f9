#include "io/stats.h"

#include "io/file_io.h"

#include <fmt/format.h>
#include <unistd.h>

#include <fstream>
#include <stdexcept>

namespace kozu {

void write_json_file(const std::filesystem::path& file, const nlohmann::json& json) {
  write_file_atomic(file, json.dump(2) + "\n");
}

}  // namespace kozu
