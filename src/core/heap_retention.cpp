#include "relaxed_connectivity/core/heap_retention.h"

#if defined(__GLIBC__)
#include <malloc.h>
#if __GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33)
#define RC_HAVE_MALLINFO2 1
#endif
#endif

namespace rc {

bool fixMallocMmapThreshold(size_t bytes) {
#if defined(__GLIBC__)
  return mallopt(M_MMAP_THRESHOLD, int(bytes)) == 1;
#else
  (void)bytes;
  return false;
#endif
}

HeapUsage heapUsage() {
  HeapUsage usage;
#ifdef RC_HAVE_MALLINFO2
  const struct mallinfo2 info = mallinfo2();
  usage.in_use = info.uordblks + info.hblkhd;
  usage.free_held = info.fordblks;
#endif
  return usage;
}

}  // namespace rc
