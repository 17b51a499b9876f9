// How much memory this process may use, and how much it has used, for the checks that run before large
// allocations (the film, voxel grids, images): a request that cannot fit stops with a message naming the need
// and the limit instead of failing inside an allocation.
#pragma once

#include <cstddef>
#include <string>

namespace kozu {

struct MemoryLimit {
  size_t bytes = 0;    // the smallest of the limits below that is set
  std::string source;  // which one: "physical memory", "cgroup memory.max", "RLIMIT_AS", "RLIMIT_DATA",
                       // "KOZU_MEMORY_LIMIT"
};
// The memory this process may use in all: physical memory, lowered by a cgroup (v2) limit, rlimits, or the
// environment variable KOZU_MEMORY_LIMIT (bytes, or with a suffix K, M, G or T: "12G"), which a render farm can set
// to keep kozu within a machine's share. A KOZU_MEMORY_LIMIT that is not such a number is ignored.
MemoryLimit memory_limit();
// Parses a byte count with an optional binary suffix (K, M, G, T); 0 when the text is not one.
size_t parse_byte_count(const std::string& text);

// Resident set size now and at its peak, in bytes (0 where unknown).
size_t current_rss_bytes();
size_t peak_rss_bytes();
// What is left of the limit now: limit.bytes less the resident set (negative past the limit).
double memory_left(const MemoryLimit& limit);

// "1.5 GiB", "640 MiB", "12 KiB", "100 bytes".
std::string format_bytes(double bytes);

}  // namespace kozu
