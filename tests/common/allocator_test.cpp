// The allocator set-up of long runs (common/app.hpp): large blocks stay out of the heap after one was freed.
#include "tachi/common/app.hpp"

#include <gtest/gtest.h>
#include <malloc.h>

#include <cstdlib>
#include <cstring>

namespace {

// ASan's allocator answers neither mallopt nor mallinfo2; the sanitized unit tests are built with gcc.
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSanitizedAllocator = true;
#else
constexpr bool kSanitizedAllocator = false;
#endif

// Bytes in blocks that have their own mapping.
std::size_t mapped_bytes() { return mallinfo2().hblkhd; }

TEST(LongRunAllocator, AfterALargeBlockIsFreedTheNextLargeOneStillGetsItsOwnMapping) {
  if (kSanitizedAllocator) GTEST_SKIP() << "the sanitizer's allocator replaces glibc's";
  // Through the loop every node runs: it sets the allocator up before its first tick.
  tachi::common::run_until_stopped([] { return false; });
  // A block is mapped on its own only when the heap has no free room for it: give the heap's free top
  // back first (the tests before this one leave some), and use blocks larger than any hole they leave.
  ::malloc_trim(0);

  // glibc alone raises its threshold to 4 MiB when the first block is freed (as it did to 1 MiB with each
  // of Cyclone's receive buffers), and the second block then comes from the heap, whose freed pages stay.
  constexpr std::size_t kBlock = std::size_t{4} << 20;
  for (int round = 0; round < 2; ++round) {
    const std::size_t before = mapped_bytes();
    auto* block = static_cast<char*>(std::malloc(kBlock));
    ASSERT_NE(block, nullptr);
    std::memset(block, 1, kBlock);
    EXPECT_GE(mapped_bytes(), before + kBlock) << "block " << round + 1 << " came from the heap";
    std::free(block);
    EXPECT_EQ(mapped_bytes(), before) << "freeing block " << round + 1 << " gave its mapping back";
  }
}

}  // namespace
