#include "paged_heap.h"

#include <malloc.h>

namespace fragg::cli {

namespace {
constexpr int kMmapThresholdBytes = 1 << 20;
}  // namespace

bool compactHeapForPaging() {
  // mallopt returns 1 on success. M_MMAP_THRESHOLD set explicitly also stops glibc's dynamic
  // threshold (which would climb to 32 MiB as the rounds free their buffers).
  const bool arenas = mallopt(M_ARENA_MAX, 1) == 1;
  const bool threshold = mallopt(M_MMAP_THRESHOLD, kMmapThresholdBytes) == 1;
  return arenas && threshold;
}

}  // namespace fragg::cli
