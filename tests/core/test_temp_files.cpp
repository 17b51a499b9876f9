// Temporary files (core/temp_files.h): guards remove their files, and a thread that ends the process removes every
// registered one, waiting for a creation under way. The exit tests run in a forked child: the exit flag is
// process-wide and the child ends the process as kozu's stop-signal watcher does.
#include "core/temp_files.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

namespace kozu::test {
namespace {

namespace fs = std::filesystem;

fs::path fresh_path(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("kozu-temp-files-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const fs::path p = dir / name;
  fs::remove(p);
  return p;
}

void touch(const fs::path& p) {
  const int fd = ::open(p.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd >= 0) ::close(fd);
}

TEST(TempFiles, AGuardRemovesItsFileUnlessReleased) {
  const fs::path a = fresh_path("a.tmp"), b = fresh_path("b.tmp");
  {
    TempFileGuard guard(a);
    touch(a);
    ASSERT_TRUE(fs::exists(a));
  }
  EXPECT_FALSE(fs::exists(a));
  {
    TempFileGuard guard(b);
    touch(b);
    guard.release();
  }
  EXPECT_TRUE(fs::exists(b));
  fs::remove(b);
}

TEST(TempFiles, TheSignalPathRemovesRegisteredFiles) {
  const fs::path a = fresh_path("signal.tmp");
  TempFileGuard guard(a);
  touch(a);
  remove_temp_files_on_signal();
  EXPECT_FALSE(fs::exists(a));
}

// Runs body in a forked child that must end with _exit(0) within 5 s; returns the child's status.
template <class Body>
int in_child(Body body) {
  const pid_t pid = fork();
  if (pid == 0) {
    alarm(5);  // a child blocked for good dies of SIGALRM, which the test reports
    body();
    _exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return status;
}

// In the child, with a writer thread started: ends the process as the stop-signal watcher does, 20 ms in: the
// removal, then 200 ms (its message, the teardown) before the child's _exit.
void exit_as_the_watcher_does() {
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  remove_temp_files_before_exit();
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
}

void expect_no_file_left(int status, const fs::path& p) {
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status;
  EXPECT_FALSE(fs::exists(p));
  fs::remove(p);
}

TEST(TempFiles, AnExitWaitsForACreationUnderWay) {
  // A writer registers its file and opens it 100 ms later, inside a creation window; meanwhile another thread ends
  // the process, taking 200 ms between removing the files and exiting (writing its message, tearing down). Without
  // the wait for the window the file would be made after the removal and left behind (the CI failure of
  // CliSignals.SignalAtAnyMomentLeavesNoTemporaryFile).
  const fs::path p = fresh_path("under-way.tmp");
  const int status = in_child([&] {
    std::thread writer([&] {
      TempFileGuard guard(p);
      create_temp_file([&] {
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        touch(p);
      });
      std::this_thread::sleep_for(std::chrono::seconds(10));
    });
    writer.detach();
    exit_as_the_watcher_does();
  });
  expect_no_file_left(status, p);
}

TEST(TempFiles, NoCreationStartsOnceAnExitHasBegun) {
  const fs::path p = fresh_path("late.tmp");
  const int status = in_child([&] {
    std::thread writer([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      TempFileGuard guard(p);
      create_temp_file([&] { touch(p); });  // blocks: the exit began at 20 ms
    });
    writer.detach();
    exit_as_the_watcher_does();
  });
  expect_no_file_left(status, p);
}

}  // namespace
}  // namespace kozu::test
