// Tables that depend on a material's roughness (compensation curves, coupled lobes), for a roughness that may be
// a texture: exact for a constant, one set per 1/255 step of a textured value (an 8-bit texture's own steps),
// built on first use (thread-safe) and kept for the material's life: the tables are far too slow to build per hit
// (a subsurface boundary's transmittance integrates 32 × 16384 BSDF samples, about 65 ms), and 256 levels bound
// the memory (standard.h, conductor.h, plastic.h, dielectric.h, subsurface.h).
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>

namespace kozu {

template <class T>
class RoughnessTables {
 public:
  static constexpr int kLevels = 256;

  RoughnessTables() = default;
  // make(x) builds the tables for the key x (a roughness-like value in [0, 1]; what x means is make's business).
  // constant: the only key there will be (built now, not quantized); nullopt: keys vary, built per level.
  template <class Make>
  RoughnessTables(std::optional<float> constant, Make make) : make_(std::move(make)) {
    if (constant) fixed_ = std::make_unique<T>(make_(*constant));
  }
  RoughnessTables(const RoughnessTables&) = delete;
  RoughnessTables& operator=(const RoughnessTables&) = delete;

  // The level of x: round(255 x), x clamped to [0, 1].
  static int level(float x) { return static_cast<int>(std::lround(std::clamp(x, 0.0f, 1.0f) * 255.0f)); }
  // x rounded to its level's value (what a varying key's tables are built for).
  static float quantize(float x) { return static_cast<float>(level(x)) / 255.0f; }

  bool constant() const { return fixed_ != nullptr; }
  // The tables for x: the constant's, or those of x's level. A level is built once (std::call_once), while the
  // other levels stay readable and buildable by other threads (a subsurface level takes ~65 ms to build).
  const T& at(float x) const {
    if (fixed_) return *fixed_;
    const int l = level(x);
    if (const T* t = levels_[l].load(std::memory_order_acquire)) return *t;
    std::call_once(once_[l], [&] {
      built_[l] = std::make_unique<T>(make_(static_cast<float>(l) / 255.0f));
      levels_[l].store(built_[l].get(), std::memory_order_release);
    });
    return *built_[l];
  }

 private:
  std::function<T(float)> make_;
  std::unique_ptr<T> fixed_;
  mutable std::array<std::atomic<const T*>, kLevels> levels_{};
  mutable std::array<std::once_flag, kLevels> once_;
  mutable std::array<std::unique_ptr<T>, kLevels> built_;
};

}  // namespace kozu
