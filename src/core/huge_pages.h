// Large per-pixel buffers on transparent huge pages. A full-HD film's pixel memories ("ltc", 116 MB) took 0.32 s of
// page faults to zero on a virtual machine (28 000 faults of 4 KiB each, before the first sample of a time-limited
// render) and 0.01 s once the kernel was asked for 2 MiB pages. Linux only; elsewhere, or where the kernel says
// no (transparent_hugepage "never"), the buffer is an ordinary one.
#pragma once

#include <cstddef>
#include <cstdlib>
#include <new>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace kozu {

template <class T>
struct HugePageAllocator {
  using value_type = T;
  // Below one huge page the ordinary allocator serves: nothing to gain, and no 2 MiB of rounding.
  static constexpr size_t kHugePage = size_t{2} << 20;

  HugePageAllocator() noexcept = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) noexcept {}

  T* allocate(size_t n) {
    if (n > (static_cast<size_t>(-1) - kHugePage) / sizeof(T)) throw std::bad_array_new_length();
    const size_t bytes = n * sizeof(T);
    if (bytes < kHugePage) return static_cast<T*>(::operator new (bytes, std::align_val_t{alignof(T)}));
    // aligned_alloc wants a multiple of the alignment; the rounding is less than one huge page.
    void* p = std::aligned_alloc(kHugePage, (bytes + kHugePage - 1) / kHugePage * kHugePage);
    if (!p) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    madvise(p, bytes, MADV_HUGEPAGE);  // advice: failure leaves ordinary pages
#endif
    return static_cast<T*>(p);
  }
  void deallocate(T* p, size_t n) noexcept {
    if (n * sizeof(T) < kHugePage)
      ::operator delete (p, std::align_val_t{alignof(T)});
    else
      std::free(p);
  }
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const noexcept {
    return true;
  }
};

// A vector of one element per pixel (or per voxel): large, allocated once, touched everywhere.
template <class T>
using PixelBuffer = std::vector<T, HugePageAllocator<T>>;

}  // namespace kozu
