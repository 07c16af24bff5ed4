#include "relaxed_connectivity/core/heap_retention.h"

#if defined(__GLIBC__)
#include <malloc.h>
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

}  // namespace rc
