// KOZU_MEMORY_LIMIT (core/memory.h's memory_limit) set for one scope, for tests of what kozu refuses to allocate.
#pragma once

#include <cstdlib>
#include <optional>
#include <string>

namespace kozu::test {

// Sets KOZU_MEMORY_LIMIT for its lifetime (unset when bytes is 0), then restores what was there.
class MemoryLimitEnv {
 public:
  explicit MemoryLimitEnv(size_t bytes) {
    if (const char* old = std::getenv("KOZU_MEMORY_LIMIT")) old_ = old;
    if (bytes > 0)
      setenv("KOZU_MEMORY_LIMIT", std::to_string(bytes).c_str(), 1);
    else
      unsetenv("KOZU_MEMORY_LIMIT");
  }
  ~MemoryLimitEnv() {
    if (old_)
      setenv("KOZU_MEMORY_LIMIT", old_->c_str(), 1);
    else
      unsetenv("KOZU_MEMORY_LIMIT");
  }

 private:
  std::optional<std::string> old_;
};

}  // namespace kozu::test
