// PixelBuffer (core/huge_pages.h): large buffers start on a huge-page boundary, small ones come from the ordinary
// allocator, both hold what is written, and a size whose rounding would overflow is refused before any allocation.
#include "core/huge_pages.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <new>

namespace kozu::test {
namespace {

TEST(HugePages, LargeBuffersStartOnAHugePageAndHoldTheirValues) {
  constexpr size_t kHuge = HugePageAllocator<float>::kHugePage;
  PixelBuffer<float> big(kHuge / sizeof(float) + 3, 1.5f);  // one page and a bit: rounded up to two
  EXPECT_EQ(reinterpret_cast<uintptr_t>(big.data()) % kHuge, 0u);
  for (size_t i = 0; i < big.size(); ++i) big[i] = static_cast<float>(i);
  for (size_t i = 0; i < big.size(); i += 4097) ASSERT_EQ(big[i], static_cast<float>(i));
  big.resize(3 * big.size());  // a reallocation moves the values into a new huge-page buffer
  EXPECT_EQ(reinterpret_cast<uintptr_t>(big.data()) % kHuge, 0u);
  EXPECT_EQ(big[kHuge / sizeof(float) + 2], static_cast<float>(kHuge / sizeof(float) + 2));
  EXPECT_EQ(big.back(), 0.0f);
}

TEST(HugePages, SmallBuffersAreOrdinary) {
  PixelBuffer<double> small(100, 2.0);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(small.data()) % alignof(double), 0u);
  EXPECT_EQ(small[99], 2.0);
  PixelBuffer<double>().swap(small);
  EXPECT_TRUE(small.empty());
}

TEST(HugePages, OverflowingSizesAreRefused) {
  HugePageAllocator<uint64_t> a;
  EXPECT_THROW((void)a.allocate(static_cast<size_t>(-1) / sizeof(uint64_t)), std::bad_array_new_length);
  EXPECT_THROW((void)a.allocate(static_cast<size_t>(-1) / sizeof(uint64_t) - 1), std::bad_array_new_length);
}

}  // namespace
}  // namespace kozu::test
