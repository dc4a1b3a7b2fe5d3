// Elapsed wall time on the steady clock, for the timing fields of the stats structs.
#pragma once

#include <chrono>

namespace fragg {

/// Seconds from `t0` to now (steady clock).
[[nodiscard]] inline double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace fragg
