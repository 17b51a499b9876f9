#include "apps/stop_signals.h"

#include "core/temp_files.h"

#include <csignal>

namespace kozu::app {

namespace {

constexpr int kSignals[] = {SIGINT, SIGTERM, SIGHUP};
std::atomic<int> g_received{0};
std::atomic<std::atomic<bool>*> g_cancel{nullptr};
static_assert(std::atomic<int>::is_always_lock_free && std::atomic<bool>::is_always_lock_free,
              "a signal handler may only touch lock-free atomics");

extern "C" void on_stop_signal(int sig) {
  int none = 0;
  if (g_received.compare_exchange_strong(none, sig)) {
    if (std::atomic<bool>* cancel = g_cancel.load()) cancel->store(true);
    return;
  }
  // The second signal: leave no temporary file, then die of the signal as the sender expects.
  remove_temp_files_on_signal();
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

}  // namespace

StopSignals::StopSignals(std::atomic<bool>& cancel) {
  g_cancel.store(&cancel);
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;  // interrupted writes resume: the images must still be written
  for (int s : kSignals) sigaction(s, &sa, nullptr);
}

StopSignals::~StopSignals() {
  for (int s : kSignals) std::signal(s, SIG_DFL);
  g_cancel.store(nullptr);
}

int StopSignals::received() { return g_received.load(); }

const char* StopSignals::name(int signal) {
  switch (signal) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    case SIGHUP:
      return "SIGHUP";
    default:
      return "signal";
  }
}

}  // namespace kozu::app
