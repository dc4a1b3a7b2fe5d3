// Deadlines and cancellation for long planning queries (issue 34 item 5): frontiers of a whole
// LiDAR map at 5 cm can take minutes on a small machine, and a service answering a client that
// gave up should stop. A query given a QueryControl checks it between pieces of its work (often
// enough that it stops within milliseconds) and throws QueryStopped, leaving the map as it was.
#pragma once

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>

namespace fragg::planning {

/// A query stopped before its end: its deadline passed or it was cancelled.
class QueryStopped : public std::runtime_error {
 public:
  explicit QueryStopped(const std::string& what) : std::runtime_error(what) {}
};

struct QueryControl {
  using Clock = std::chrono::steady_clock;
  /// Stop once this time has passed (the default: never).
  Clock::time_point deadline = Clock::time_point::max();
  /// Stop once this flag is set (by another thread; null: never).
  const std::atomic<bool>* cancel = nullptr;

  /// A control whose deadline is `seconds` from now.
  [[nodiscard]] static QueryControl within(double seconds) {
    QueryControl c;
    c.deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                    std::chrono::duration<double>(seconds));
    return c;
  }
  /// Whether the query should stop now.
  [[nodiscard]] bool stopped() const {
    return (cancel && cancel->load(std::memory_order_relaxed)) ||
           (deadline != Clock::time_point::max() && Clock::now() >= deadline);
  }
  /// Throws QueryStopped (saying which) when stopped().
  void check(const char* what) const {
    if (cancel && cancel->load(std::memory_order_relaxed))
      throw QueryStopped(std::string(what) + ": cancelled");
    if (deadline != Clock::time_point::max() && Clock::now() >= deadline)
      throw QueryStopped(std::string(what) + ": deadline passed");
  }
};

/// control->check(what) when there is a control.
inline void checkQuery(const QueryControl* control, const char* what) {
  if (control) control->check(what);
}

}  // namespace fragg::planning
