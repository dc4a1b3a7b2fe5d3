// Keeping publication buffers' pages between publications. roscpp serialises every published
// message into a fresh buffer (new[] of the message's size, freed once sent). Past glibc's mmap
// threshold that buffer is mapped anew each time and every 4 KiB page of it faults in: on the
// 2-core VM a fault costs ~15 us, so a 24 MB marker update spent ~90 ms in faults alone, more
// than the copy. With a larger mmap threshold and trim threshold the freed buffer stays in the
// heap and the next publication reuses its pages.
#pragma once

#include <cstddef>

namespace fragg::ros {

/// What the map server keeps (its whole-map messages and marker updates are tens of MB).
inline constexpr size_t kKeptPublicationBytes = size_t{256} << 20;

/// Raises glibc's mmap threshold to its largest (32 MiB on 64-bit) and the trim threshold to
/// `keep_bytes`, process-wide (mallopt): freed buffers up to that size stay mapped for reuse.
/// Returns false where that is not available (not glibc) or refused. The heap's free pages
/// still go back to the system on an explicit malloc_trim (the server's ~reset does).
bool keepPublicationBuffers(size_t keep_bytes);

}  // namespace fragg::ros
