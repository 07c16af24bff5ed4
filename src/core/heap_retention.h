// Bounds the freed memory a node keeps. glibc's malloc raises its mmap threshold each time a large block is
// freed (up to 32 MiB on 64-bit), after which message-sized buffers (a full painted cloud of ~17 MB) come
// from the heap and, freed, stay in the process. Measured in 4-minute session soaks (scripts/soak_session,
// the round brush painting the scanned box): paint_model without its undo journal held 192 -> 268 MiB from
// the first minute to the end and paint_renderer 260 MiB with glibc's default; with the threshold fixed at 4
// MiB 145 -> 149 MiB (+2.2 %) and 174 -> 180 MiB; at 256 KiB less memory (128 -> 131 MiB) but every message
// buffer was mapped and faulted in afresh, and a paint tick's transfer took 3.3 instead of 2.0-2.6 ms
// (docs/benchmarks.md). Nodelets share their manager's heap: launch files set MALLOC_MMAP_THRESHOLD_ there.
#pragma once

#include <cstddef>

namespace rc {

/// Fixes the mmap threshold: blocks of at least `bytes` are mapped and unmapped on free, and glibc's dynamic
/// raising stops. Call once at the start of a node's main(); returns false where the C library has no such
/// setting (not glibc).
bool fixMallocMmapThreshold(size_t bytes = 4 << 20);

/// The process's heap as malloc sees it (all arenas): bytes handed out (mapped blocks included) and bytes
/// freed but kept in the arenas (which RSS counts where touched). Zeros where the C library cannot say (not
/// glibc 2.33+). Walks the free lists: call it at a stats rate, not per event.
struct HeapUsage {
  size_t in_use = 0, free_held = 0;
};
HeapUsage heapUsage();

}  // namespace rc
