// Per-thread bump allocator for objects that live for one path sample (BSDFs and the like).
// Reset after every sample; never frees individual objects, never calls destructors, so only
// trivially destructible types may be allocated.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <type_traits>
#include <vector>

namespace kozu {

class Arena {
 public:
  explicit Arena(size_t block_bytes = 16 * 1024) : block_bytes_(block_bytes) {}
  Arena(const Arena&) = delete;
  Arena& operator=(const Arena&) = delete;

  template <typename T, typename... Args>
  T* make(Args&&... args) {
    static_assert(std::is_trivially_destructible_v<T>, "arena objects are never destroyed");
    void* p = allocate(sizeof(T), alignof(T));
    return new (p) T(std::forward<Args>(args)...);
  }

  void* allocate(size_t bytes, size_t align) {
    uintptr_t cur = (reinterpret_cast<uintptr_t>(ptr_) + (align - 1)) & ~(uintptr_t(align) - 1);
    if (ptr_ == nullptr || cur + bytes > reinterpret_cast<uintptr_t>(end_)) {
      next_block(bytes + align);
      cur = (reinterpret_cast<uintptr_t>(ptr_) + (align - 1)) & ~(uintptr_t(align) - 1);
    }
    ptr_ = reinterpret_cast<std::byte*>(cur + bytes);
    return reinterpret_cast<void*>(cur);
  }

  // Makes all memory reusable; keeps the blocks.
  void reset() {
    block_ = 0;
    if (!blocks_.empty()) set_block(0);
  }

 private:
  void next_block(size_t min_bytes) {
    if (!blocks_.empty() && ptr_ != nullptr) ++block_;
    while (block_ < blocks_.size() && blocks_[block_].size < min_bytes) ++block_;
    if (block_ >= blocks_.size()) {
      const size_t size = std::max(block_bytes_, min_bytes);
      blocks_.push_back({std::make_unique<std::byte[]>(size), size});
      block_ = blocks_.size() - 1;
    }
    set_block(block_);
  }
  void set_block(size_t i) {
    ptr_ = blocks_[i].data.get();
    end_ = ptr_ + blocks_[i].size;
  }

  struct Block {
    std::unique_ptr<std::byte[]> data;
    size_t size;
  };
  size_t block_bytes_;
  std::vector<Block> blocks_;
  size_t block_ = 0;
  std::byte* ptr_ = nullptr;
  std::byte* end_ = nullptr;
};

}  // namespace kozu
