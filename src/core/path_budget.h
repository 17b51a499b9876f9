// Bounds on the work of one path, and the render's stop request, for the loops whose length the scene decides
// (free-flight and ratio tracking through media: their step count grows with majorant × distance, without
// limit for absurd densities, and a step below float resolution never advances at all).
//
// The renderer's watchdog raises the StopFlag at the deadline or on a signal; PathBudget polls it inside those
// loops, so a stop holds within milliseconds whatever one sample costs. Every other loop of a path is bounded
// by a fixed cap (max_depth bounces, 256 null-boundary crossings, 256 microsurface-walk orders, 16 probe hits).
#pragma once

#include <atomic>
#include <cstdint>

namespace kozu {

using StopFlag = std::atomic<bool>;

class PathBudget {
 public:
  // Tentative collisions one path may take in all its media together (free flights and shadow rays). A path
  // that reaches the cap ends there as if absorbed and is counted (truncated_paths in --stats): only media whose
  // majorant times the distance crossed exceeds about 10^6 reach it.
  static constexpr uint32_t kMaxCollisions = 1u << 20;

  explicit PathBudget(const StopFlag* stop = nullptr) : stop_(stop) {}

  // Takes one step; false once the path must end (cap reached, or the stop flag raised, polled every 1024 steps).
  bool step() {
    if (left_ == 0) return false;
    --left_;
    if ((left_ & 1023u) == 0 && stopped()) {
      left_ = 0;
      return false;
    }
    return true;
  }
  bool stopped() const { return stop_ && stop_->load(std::memory_order_relaxed); }
  // True when the path was cut by the cap (not by a stop).
  bool exhausted() const { return left_ == 0 && !stopped(); }
  // Steps taken so far (tentative_collisions in --stats).
  uint32_t used() const { return kMaxCollisions - left_; }

 private:
  const StopFlag* stop_;
  uint32_t left_ = kMaxCollisions;
};

}  // namespace kozu
