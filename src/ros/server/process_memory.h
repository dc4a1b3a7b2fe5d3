// The process's resident memory and giving freed heap back to the system (glibc), so that a
// ~reset shows up in the RSS a user watches.
#pragma once

#include <cstddef>

namespace fragg::ros {

/// Resident set size of this process in bytes (/proc/self/statm), 0 when unreadable.
size_t residentBytes();

/// Returns the heap's free pages to the system (glibc malloc_trim); false where that is not
/// available or nothing was released.
bool releaseFreeHeap();

}  // namespace fragg::ros
