// The thread count behind every "threads" setting: n, or every core for 0.
#pragma once

#include <omp.h>

#include <algorithm>

namespace fragg {

/// `requested` threads, or every core (at least one) for 0 or less.
inline int threadCount(int requested) {
  return requested > 0 ? requested : std::max(1, omp_get_max_threads());
}

}  // namespace fragg
