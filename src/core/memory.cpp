#include "core/memory.h"

#include <fmt/format.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <string>

namespace kozu {

MemoryLimit memory_limit() {
  MemoryLimit limit{std::numeric_limits<size_t>::max(), "no limit"};
  const auto lower = [&](size_t bytes, const char* source) {
    if (bytes > 0 && bytes < limit.bytes) limit = {bytes, source};
  };
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  if (pages > 0 && page > 0) lower(static_cast<size_t>(pages) * static_cast<size_t>(page), "physical memory");
  // cgroup v2: "max" or a byte count.
  std::ifstream cg("/sys/fs/cgroup/memory.max");
  std::string value;
  if (cg >> value && value != "max") {
    try {
      lower(static_cast<size_t>(std::stoull(value)), "cgroup memory.max");
    } catch (const std::exception&) {
    }
  }
  struct rlimit rl {};
  if (getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY) lower(rl.rlim_cur, "RLIMIT_AS");
  if (getrlimit(RLIMIT_DATA, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY) lower(rl.rlim_cur, "RLIMIT_DATA");
  if (const char* env = std::getenv("KOZU_MEMORY_LIMIT")) lower(parse_byte_count(env), "KOZU_MEMORY_LIMIT");
  return limit;
}

size_t parse_byte_count(const std::string& text) {
  size_t i = 0;
  uint64_t value = 0;
  while (i < text.size() && text[i] >= '0' && text[i] <= '9') {
    if (value > (uint64_t{1} << 50)) return 0;  // beyond any machine: not a limit
    value = value * 10 + uint64_t(text[i++] - '0');
  }
  if (i == 0) return 0;
  int shift = 0;
  if (i < text.size()) {
    switch (text[i++]) {
      case 'K': case 'k': shift = 10; break;
      case 'M': case 'm': shift = 20; break;
      case 'G': case 'g': shift = 30; break;
      case 'T': case 't': shift = 40; break;
      default: return 0;
    }
    if (i < text.size() && (text[i] == 'i' || text[i] == 'B')) ++i;  // "Gi", "GB"
    if (i < text.size() && text[i] == 'B') ++i;                      // "GiB"
  }
  if (i != text.size() || value > (uint64_t{1} << (62 - shift))) return 0;
  return static_cast<size_t>(value << shift);
}

double memory_left(const MemoryLimit& limit) {
  return static_cast<double>(limit.bytes) - static_cast<double>(current_rss_bytes());
}

size_t current_rss_bytes() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return 0;
  unsigned long size = 0, resident = 0;
  const int n = std::fscanf(f, "%lu %lu", &size, &resident);
  std::fclose(f);
  const long page = sysconf(_SC_PAGE_SIZE);
  return n == 2 && page > 0 ? static_cast<size_t>(resident) * static_cast<size_t>(page) : 0;
}

size_t peak_rss_bytes() {
  struct rusage usage {};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0;
  return static_cast<size_t>(usage.ru_maxrss) * 1024;  // Linux reports kilobytes
}

std::string format_bytes(double bytes) {
  constexpr double kKi = 1024.0;
  if (bytes >= kKi * kKi * kKi) return fmt::format("{:.1f} GiB", bytes / (kKi * kKi * kKi));
  if (bytes >= kKi * kKi) return fmt::format("{:.0f} MiB", bytes / (kKi * kKi));
  if (bytes >= kKi) return fmt::format("{:.0f} KiB", bytes / kKi);
  return fmt::format("{:.0f} bytes", bytes);
}

}  // namespace kozu
