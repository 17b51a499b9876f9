// SIGINT, SIGTERM and SIGHUP during a render (Ctrl-C, a render farm's or a contest harness's stop): the first
// one stops sampling and lets kozu write its images and statistics, then exit with 128 + the signal number
// (130, 143, 129); a second one removes any temporary output file and ends the process at once by the
// signal's default action.
#pragma once

#include <atomic>

namespace kozu::app {

class StopSignals {
 public:
  // From now on, the first stop signal raises `cancel`.
  explicit StopSignals(std::atomic<bool>& cancel);
  // Restores the default actions (a signal after this ends the process at once).
  ~StopSignals();
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

  // The first signal received (0: none).
  static int received();
  static const char* name(int signal);  // "SIGTERM", ...
};

}  // namespace kozu::app
