// Time since the process started, as a contest harness or a render farm measures a run: from the exec, so the
// dynamic loader's and static initializers' time count too (`kozu render --budget`).
#pragma once

namespace kozu {

// Seconds since this process started (Linux: /proc/self/stat's start time against CLOCK_BOOTTIME, 10 ms steps);
// where that cannot be read, since the first call.
double seconds_since_process_start();

}  // namespace kozu
