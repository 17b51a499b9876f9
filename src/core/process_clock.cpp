#include "core/process_clock.h"

#include <time.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <string>

namespace kozu {

namespace {

// The process's start in seconds after boot, or a negative value when /proc cannot say.
double start_after_boot() {
  std::ifstream in("/proc/self/stat");
  std::string line;
  if (!std::getline(in, line)) return -1.0;
  // Field 2 (the command name) may hold spaces and parentheses: the fields after it follow the last ')'.
  const size_t close = line.rfind(')');
  if (close == std::string::npos) return -1.0;
  std::istringstream fields(line.substr(close + 1));
  std::string field;
  // Fields 3 .. 22; field 22 is the start time in clock ticks after boot.
  for (int i = 3; i <= 22; ++i)
    if (!(fields >> field)) return -1.0;
  const long ticks = sysconf(_SC_CLK_TCK);
  if (ticks <= 0) return -1.0;
  try {
    return static_cast<double>(std::stoull(field)) / static_cast<double>(ticks);
  } catch (...) {
    return -1.0;
  }
}

double boot_seconds() {
  timespec t{};
  if (clock_gettime(CLOCK_BOOTTIME, &t) != 0) return -1.0;
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace

double seconds_since_process_start() {
  static const double start = start_after_boot();
  static const auto first_call = std::chrono::steady_clock::now();
  const double now = boot_seconds();
  if (start >= 0.0 && now >= start) return now - start;
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - first_call).count();
}

}  // namespace kozu
