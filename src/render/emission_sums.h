// The film's sums of the visible emission (PixelFeatures::emission: emitters seen directly or through perfectly
// specular vertices), stored sparsely: most pixels of most images see no emitter, so their sums stay zero and take
// no memory. Pixels come in blocks of 8 × 8, each allocated when one of its pixels first sees an emitter; a pixel
// costs 28 bytes inside an allocated block and an eighth of a byte (its block's pointer) outside. Dense storage took
// 58 MB at 1920 × 1080 whatever the image showed.
//
// Thread safety: as the film's, one thread per pixel at a time; a block's allocation is a compare-and-swap, so two
// threads rendering pixels of the same block may add to it at once.
#pragma once

#include "core/math.h"

#include <atomic>
#include <cstddef>
#include <memory>
#include <vector>

namespace kozu {

class EmissionSums {
 public:
  // One pixel's sums: over the samples that went into the film, over the even-numbered ones, and the sum of the
  // squared luminance.
  struct Pixel {
    Vec3 sum{0.0f}, even{0.0f};
    float sq = 0.0f;
  };

  EmissionSums() = default;
  EmissionSums(int width, int height)
      : width_(width), blocks_x_((width + kBlock - 1) / kBlock),
        blocks_(static_cast<size_t>(blocks_x_) * ((height + kBlock - 1) / kBlock), nullptr) {}
  EmissionSums(const EmissionSums& o) : width_(o.width_), blocks_x_(o.blocks_x_), blocks_(o.blocks_.size(), nullptr) {
    for (size_t b = 0; b < blocks_.size(); ++b)
      if (o.blocks_[b]) blocks_[b] = new Block(*o.blocks_[b]);
  }
  EmissionSums(EmissionSums&& o) noexcept { swap(o); }
  EmissionSums& operator=(EmissionSums o) noexcept {
    swap(o);
    return *this;
  }
  ~EmissionSums() {
    for (Block* b : blocks_) delete b;
  }

  // Pixel (x, y) of the film's window (0-based), allocating its block when it has none.
  Pixel& at(int x, int y) {
    Block*& slot = blocks_[block_index(x, y)];
    Block* block = std::atomic_ref<Block*>(slot).load(std::memory_order_acquire);
    if (!block) block = allocate(slot);
    return block->pixels[offset(x, y)];
  }
  // Its sums, zero when its block was never allocated.
  Pixel get(int x, int y) const {
    const Block* block = blocks_[block_index(x, y)];
    return block ? block->pixels[offset(x, y)] : Pixel{};
  }
  // By row-major index over the window.
  Pixel get(size_t i) const { return get(column(i), row(i)); }
  // Pixel i set to e, allocating its block only when e is not zero (sums read from a file or another rank).
  void set(size_t i, const Pixel& e) {
    if (e.sum == Vec3(0.0f) && e.even == Vec3(0.0f) && e.sq == 0.0f)
      clear(i);
    else
      at(column(i), row(i)) = e;
  }
  // Pixel i set to zero (without allocating).
  void clear(size_t i) {
    const int x = column(i), y = row(i);
    if (Block* block = blocks_[block_index(x, y)]) block->pixels[offset(x, y)] = Pixel{};
  }
  // Blocks allocated.
  size_t blocks() const {
    size_t n = 0;
    for (const auto& b : blocks_) n += b != nullptr;
    return n;
  }

 private:
  static constexpr int kBlock = 8;
  struct Block {
    Pixel pixels[kBlock * kBlock];
  };
  int column(size_t i) const { return static_cast<int>(i % static_cast<size_t>(width_)); }
  int row(size_t i) const { return static_cast<int>(i / static_cast<size_t>(width_)); }
  size_t block_index(int x, int y) const { return static_cast<size_t>(y / kBlock) * blocks_x_ + x / kBlock; }
  static int offset(int x, int y) { return (y % kBlock) * kBlock + x % kBlock; }
  // The first thread to need the block installs it; another that raced it frees its own and takes the winner's.
  static Block* allocate(Block*& slot) {
    auto fresh = std::make_unique<Block>();
    Block* expected = nullptr;
    if (std::atomic_ref<Block*>(slot).compare_exchange_strong(expected, fresh.get(), std::memory_order_acq_rel))
      return fresh.release();
    return expected;
  }
  void swap(EmissionSums& o) noexcept {
    std::swap(width_, o.width_);
    std::swap(blocks_x_, o.blocks_x_);
    std::swap(blocks_, o.blocks_);
  }

  int width_ = 0, blocks_x_ = 0;
  std::vector<Block*> blocks_;  // owned; null where no pixel of the block has seen an emitter
};

}  // namespace kozu
