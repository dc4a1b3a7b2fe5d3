// glibc's mmap and trim thresholds raised for the publication buffers.
#include "fragg_map/ros/publish_buffers.h"

#include <climits>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace fragg::ros {

bool keepPublicationBuffers(size_t keep_bytes) {
#if defined(__GLIBC__)
  // glibc refuses an mmap threshold above HEAP_MAX_SIZE / 2 (32 MiB with 64-bit pointers).
  constexpr int kLargestMmapThreshold = 32 * 1024 * 1024;
  const int trim =
      keep_bytes > static_cast<size_t>(INT_MAX) ? INT_MAX : static_cast<int>(keep_bytes);
  return mallopt(M_MMAP_THRESHOLD, kLargestMmapThreshold) == 1 &&
         mallopt(M_TRIM_THRESHOLD, trim) == 1;
#else
  (void)keep_bytes;
  return false;
#endif
}

}  // namespace fragg::ros
