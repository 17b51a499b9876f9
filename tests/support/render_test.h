// Helpers for scene-level tests: render JSON text in-process and read back the film.
#pragma once

#include "integrators/path.h"
#include "io/image_io.h"
#include "render/film.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "support/sanitizer.h"

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace kozu::test {

struct TestRender {
  std::unique_ptr<Scene> scene;
  Film film;
  RenderResult result;
};

// Loads `json` (as if from a file named scene.json in base_dir) and renders it.
TestRender render_json(const std::string& json, int spp, int threads = 0, uint64_t seed = 0,
                       const std::filesystem::path& base_dir = ".");

// Mean over all pixels and the standard error of that mean (from the per-pixel variances).
struct ImageStats {
  Rgb mean{0.0f};
  Rgb standard_error{0.0f};
};
ImageStats image_stats(const Film& film);

// The film against a reference image of the same size, noise-aware: each block × block pixels' mean, per channel,
// must lie within z standard errors of the reference's (the standard error from the film's own per-pixel variances;
// the reference's noise is neglected), z the two-sided normal quantile at a Šidák-corrected 1 % over all blocks and
// channels. Failures are reported as test failures.
void expect_matches_reference(const Film& film, const Image& ref, int block = 8);

// Source tree (for scenes/ and tests/data/); KOZU_SOURCE_DIR in the environment overrides it.
std::filesystem::path source_dir();
// The kozu executable built with the tests; KOZU_BINARY in the environment overrides it.
std::filesystem::path kozu_binary();

// Runs a shell command, capturing stderr+stdout; returns the exit status.
int run_command(const std::string& command, std::string* output);

// A shell command run in the background (stdout and stderr into a log file), to be signalled and waited for.
class ChildProcess {
 public:
  ChildProcess(const std::string& command, const std::filesystem::path& log);
  ~ChildProcess();  // kills the process if it is still running
  void signal(int sig) const;
  // Waits up to `seconds` until the process has a handler for sig (SigCgt in /proc/PID/status): a fixed sleep
  // is not enough on a loaded machine, where starting the process alone can take seconds. The shell before its
  // exec does not count.
  bool wait_until_catches(int sig, double seconds) const;
  // Waits up to `seconds`; the raw wait status, or nullopt on timeout.
  std::optional<int> wait(double seconds);
  double seconds_since_start() const;
  std::string log() const;

 private:
  pid_t pid_ = -1;
  bool reaped_ = false;
  std::filesystem::path log_;
  std::chrono::steady_clock::time_point start_;
};

// An untiled float RGB EXR of f(x, y, channel), for the image checks' tests.
std::filesystem::path write_test_exr(const std::filesystem::path& file, int width, int height,
                                     const std::function<float(int, int, int)>& f);

// A fresh empty directory under the system temp folder, removed on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::filesystem::path& path() const { return path_; }
  // Writes contents (binary) to path() / name and returns that path; a failed write fails the test.
  std::filesystem::path write(const std::string& name, std::string_view contents) const;

 private:
  std::filesystem::path path_;
};

// `kozu render sub/scene.json -o sub/out.exr --spp 1` run from `dir` (so the texture cache is sub/.kozu-tx, a relative
// folder), for a 4 x 4 view of a quad whose material is `material` (JSON); sub/bumps.exr is a striped normal map the
// material may name. The exit status, the command's output, and the names of the files left in sub/.kozu-tx.
struct RelativeCacheRender {
  int status = -1;
  std::string output;
  std::vector<std::string> cached;
};
RelativeCacheRender render_with_relative_cache(const TempDir& dir, const std::string& material);

}  // namespace kozu::test
