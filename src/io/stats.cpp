#include "io/stats.h"

#include "io/file_io.h"

#include <fmt/format.h>
#include <sys/resource.h>
#include <unistd.h>

#include <fstream>
#include <stdexcept>

namespace kozu {

size_t peak_rss_bytes() {
  struct rusage usage {};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0;
  return static_cast<size_t>(usage.ru_maxrss) * 1024;  // Linux reports kilobytes
}

void write_json_file(const std::filesystem::path& file, const nlohmann::json& json) {
  write_file_atomic(file, json.dump(2) + "\n");
}

}  // namespace kozu
