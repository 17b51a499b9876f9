// SIGINT, SIGTERM and SIGHUP (Ctrl-C, a render farm's or a contest harness's stop), for every command.
//
// Outside a cooperative section, the first signal ends the command at once: a watcher thread (woken through a
// semaphore, the one async-signal-safe way to reach it) prints one line, removes every registered temporary file
// (core/temp_files.h) and exits with 128 + the signal (130, 143, 129). So loading a large glTF, converting a texture,
// fitting a table or any other long step stops within milliseconds and leaves no partial file, without each of them
// polling a flag.
//
// Inside a cooperative section (`kozu render` while it samples and writes) the first signal only raises the
// section's cancel flag: sampling stops and the images of the samples taken are written; the command then exits with
// 128 + the signal itself. In both cases a second signal removes any temporary file and ends the process at once by
// the signal's default action.
#pragma once

#include <atomic>
#include <string>

namespace kozu::app {

class StopSignals {
 public:
  // Installs the handlers and the watcher for the whole run; `command` names the command in the message
  // ("kozu maketx").
  static void install();
  static void set_command(const std::string& command);

  // While one lives, the first signal raises `cancel` instead of ending the process.
  class Cooperative {
   public:
    explicit Cooperative(std::atomic<bool>& cancel);
    ~Cooperative();
    Cooperative(const Cooperative&) = delete;
    Cooperative& operator=(const Cooperative&) = delete;
  };

  // The first signal received (0: none).
  static int received();
  static const char* name(int signal);  // "SIGTERM", ...
};

}  // namespace kozu::app
