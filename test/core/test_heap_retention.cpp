// fixMallocMmapThreshold: after a large block is freed, a block above the fixed threshold is still mapped (so
// freeing it returns its memory), where glibc's dynamic threshold would have raised itself and served it from
// the heap.
#include "relaxed_connectivity/core/heap_retention.h"

#include <gtest/gtest.h>

#include "../sanitizer_support.h"

#include <cstdlib>
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
#include <malloc.h>
#define RC_HAVE_MALLINFO2 1
#endif

namespace rc {
namespace {

TEST(HeapRetention, BlocksAboveTheFixedThresholdStayMappedAfterLargerOnesWereFreed) {
#if defined(RC_SANITIZER_ALLOCATOR)
  GTEST_SKIP() << "glibc's heap statistics do not see the sanitizer's allocator";
#endif
#ifndef RC_HAVE_MALLINFO2
  GTEST_SKIP() << "needs glibc (mallopt, mallinfo2 from glibc 2.33)";
#else
  ASSERT_TRUE(fixMallocMmapThreshold(256 * 1024));
  void* large = std::malloc(8 << 20);  // 8 MiB, mapped; freeing it would raise a dynamic threshold to 8 MiB
  ASSERT_NE(large, nullptr);
  std::free(large);
  const size_t mapped_before = mallinfo2().hblks;
  void* message = std::malloc(1 << 20);  // a 1 MiB message buffer
  ASSERT_NE(message, nullptr);
  EXPECT_EQ(mallinfo2().hblks, mapped_before + 1) << "the 1 MiB block came from the heap";
  std::free(message);
  EXPECT_EQ(mallinfo2().hblks, mapped_before);  // unmapped: back to the system
#endif
}

TEST(HeapRetention, HeapUsageCountsWhatIsHandedOutAndFreed) {
#if defined(RC_SANITIZER_ALLOCATOR)
  GTEST_SKIP() << "glibc's heap statistics do not see the sanitizer's allocator";
#endif
#ifndef RC_HAVE_MALLINFO2
  GTEST_SKIP() << "needs glibc 2.33+ (mallinfo2)";
#else
  const HeapUsage before = heapUsage();
  void* block = std::malloc(1 << 16);  // below the mmap threshold: from an arena
  ASSERT_NE(block, nullptr);
  const HeapUsage holding = heapUsage();
  EXPECT_GE(holding.in_use, before.in_use + (1 << 16));
  EXPECT_LE(holding.in_use, before.in_use + (1 << 16) + 64);
  std::free(block);
  EXPECT_EQ(heapUsage().in_use, before.in_use);
#endif
}

}  // namespace
}  // namespace rc
