#include "core/temp_files.h"

#include <unistd.h>

#include <atomic>
#include <cstring>
#include <system_error>

namespace kozu {

namespace {

// A fixed table a signal handler can read without locks or allocation. A slot is claimed (free → writing), its
// path written, then published (release); the handler reads only published slots (acquire).
enum SlotState : int { kFree, kWriting, kPublished };
struct Slot {
  std::atomic<int> state{kFree};
  char path[4096] = {};
};
constexpr int kSlots = 32;
Slot g_slots[kSlots];

}  // namespace

TempFileGuard::TempFileGuard(std::filesystem::path file) : file_(std::move(file)) {
  const std::string& s = file_.native();
  if (s.size() >= sizeof(Slot::path)) return;  // still removed by the destructor, just not by a signal
  for (int i = 0; i < kSlots; ++i) {
    int expected = kFree;
    if (!g_slots[i].state.compare_exchange_strong(expected, kWriting, std::memory_order_acquire)) continue;
    std::memcpy(g_slots[i].path, s.c_str(), s.size() + 1);
    g_slots[i].state.store(kPublished, std::memory_order_release);
    slot_ = i;
    return;
  }
}

TempFileGuard::~TempFileGuard() {
  if (file_.empty()) return;
  std::error_code ec;
  std::filesystem::remove(file_, ec);
  release();
}

void TempFileGuard::release() {
  if (slot_ >= 0) g_slots[slot_].state.store(kFree, std::memory_order_release);
  slot_ = -1;
  file_.clear();
}

void remove_temp_files_on_signal() {
  for (Slot& slot : g_slots)
    if (slot.state.load(std::memory_order_acquire) == kPublished) unlink(slot.path);
}

}  // namespace kozu
