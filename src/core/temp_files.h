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

// Brackets the creation of a registered temporary file (its guard made, then the file opened) outside the render's
// cooperative sections, where a stop signal ends the process from another thread (remove_temp_files_before_exit):
// once that has begun, a creation blocks until the process ends instead of making a file nobody will remove.
class TempFileCreation {
 public:
  TempFileCreation();
  ~TempFileCreation();
  TempFileCreation(const TempFileCreation&) = delete;
  TempFileCreation& operator=(const TempFileCreation&) = delete;
};

// Runs create, the call that makes a registered temporary file (an open), inside a TempFileCreation: every writer of
// one (image, checkpoint, voxel and text files) creates its file this way.
template <class F>
decltype(auto) create_temp_file(F&& create) {
  const TempFileCreation window;
  return create();
}

// For a thread that is about to end the process: stops new creations, waits (at most half a second) for those under
// way, then unlinks every registered temporary file. A SIGTERM in CI once landed between the removal and an output
// probe's creation, and the probe was left behind.
void remove_temp_files_before_exit();

}  // namespace kozu
