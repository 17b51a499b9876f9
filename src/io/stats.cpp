#include "io/stats.h"

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
  const std::filesystem::path tmp = file.string() + fmt::format(".{}.tmp", static_cast<long>(getpid()));
  {
    std::ofstream out(tmp);
    if (!out) throw std::runtime_error(fmt::format("{}: cannot write: {}", file.string(), std::strerror(errno)));
    out << json.dump(2) << "\n";
    if (!out) throw std::runtime_error(fmt::format("{}: write failed", file.string()));
  }
  std::error_code ec;
  std::filesystem::rename(tmp, file, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw std::runtime_error(fmt::format("{}: cannot move into place: {}", file.string(), ec.message()));
  }
}

}  // namespace kozu
