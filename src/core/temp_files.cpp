#include "core/temp_files.h"

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <system_error>
#include <thread>

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
// TempFileCreation against remove_temp_files_before_exit, Dekker-style (sequentially consistent): either the
// creation sees the exit begun and does not create, or the exit sees the creation under way and waits for it.
std::atomic<int> g_creating{0};
std::atomic<bool> g_exiting{false};

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

TempFileCreation::TempFileCreation() {
  g_creating.fetch_add(1);
  if (!g_exiting.load()) return;
  g_creating.fetch_sub(1);
  for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));  // the process is ending
}

TempFileCreation::~TempFileCreation() { g_creating.fetch_sub(1); }

void remove_temp_files_before_exit() {
  g_exiting.store(true);
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
  while (g_creating.load() > 0 && std::chrono::steady_clock::now() < give_up)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  remove_temp_files_on_signal();
}

}  // namespace kozu
