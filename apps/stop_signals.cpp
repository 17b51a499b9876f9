#include "apps/stop_signals.h"

#include "core/temp_files.h"

#include <semaphore.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <mutex>
#include <thread>

namespace kozu::app {

namespace {

constexpr int kSignals[] = {SIGINT, SIGTERM, SIGHUP};
std::atomic<int> g_received{0};
std::atomic<std::atomic<bool>*> g_cancel{nullptr};
sem_t g_wake;
char g_command[64] = "kozu";
static_assert(std::atomic<int>::is_always_lock_free && std::atomic<bool>::is_always_lock_free &&
                  std::atomic<std::atomic<bool>*>::is_always_lock_free,
              "a signal handler may only touch lock-free atomics");

extern "C" void on_stop_signal(int sig) {
  int none = 0;
  if (g_received.compare_exchange_strong(none, sig)) {
    if (std::atomic<bool>* cancel = g_cancel.load()) cancel->store(true);
    const int saved = errno;
    sem_post(&g_wake);  // async-signal-safe
    errno = saved;
    return;
  }
  // The second signal: leave no temporary file, then die of the signal as the sender expects.
  remove_temp_files_on_signal();
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

void write_stderr(const char* s) {
  for (size_t n = std::strlen(s); n > 0;) {
    const ssize_t w = ::write(STDERR_FILENO, s, n);
    if (w <= 0) return;
    s += w;
    n -= static_cast<size_t>(w);
  }
}

// Waits for the first signal; outside a cooperative section it ends the process.
void watch() {
  while (sem_wait(&g_wake) != 0 && errno == EINTR) {
  }
  if (g_cancel.load()) return;  // a cooperative section stops by itself
  const int sig = g_received.load();
  remove_temp_files_before_exit();  // not the signal handler: it may wait for a file being created
  char line[192];
  std::snprintf(line, sizeof line, "error: %s: interrupted by %s; nothing written\n", g_command,
                StopSignals::name(sig));
  write_stderr(line);
  std::_Exit(128 + sig);
}

}  // namespace

void StopSignals::install() {
  static std::once_flag once;
  std::call_once(once, [] {
    sem_init(&g_wake, 0, 0);
    std::thread(watch).detach();
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART;  // interrupted writes resume: the images must still be written
    for (int s : kSignals) sigaction(s, &sa, nullptr);
  });
}

void StopSignals::set_command(const std::string& command) {
  std::snprintf(g_command, sizeof g_command, "%s", command.c_str());
}

StopSignals::Cooperative::Cooperative(std::atomic<bool>& cancel) {
  g_cancel.store(&cancel);
  // A signal that came just before: the watcher may already be ending the process; if it has not looked yet,
  // the section sees the flag raised.
  if (g_received.load()) cancel.store(true);
}

StopSignals::Cooperative::~Cooperative() {
  g_cancel.store(nullptr);
  // A signal received inside the section was handled there; one that arrives after ends the process.
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
