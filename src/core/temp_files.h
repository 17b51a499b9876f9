// Temporary files being written (outputs go to a temporary file that is renamed into place), registered so
// that nothing is left behind on any exit path: a guard removes its file unless released (errors, exceptions),
// and a signal handler that ends the process calls remove_temp_files_on_signal() first.
#pragma once

#include <filesystem>

namespace kozu {

class TempFileGuard {
 public:
  explicit TempFileGuard(std::filesystem::path file);
  ~TempFileGuard();
  TempFileGuard(const TempFileGuard&) = delete;
  TempFileGuard& operator=(const TempFileGuard&) = delete;
  const std::filesystem::path& path() const { return file_; }
  // The file was renamed into place (or is otherwise no longer temporary): keep it.
  void release();

 private:
  std::filesystem::path file_;
  int slot_ = -1;  // in the signal handler's table; -1 when the table was full or the path too long
};

// Async-signal-safe: unlinks every temporary file still registered.
void remove_temp_files_on_signal();

}  // namespace kozu
