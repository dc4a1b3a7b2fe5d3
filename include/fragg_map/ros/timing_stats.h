// Insertion times of the map server: last, mean over every sample, p99 over the most recent
// samples (a bounded window, so memory stays constant on long runs). ROS-free; not
// thread-safe (the server guards it with its stats mutex).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace fragg::ros {

class TimingStats {
 public:
  /// `window` samples are kept for the percentile (>= 1).
  explicit TimingStats(size_t window = 10000);

  void add(double ms);
  void clear();

  uint64_t count() const { return count_; }
  double lastMs() const { return last_ms_; }
  double meanMs() const { return count_ ? sum_ms_ / static_cast<double>(count_) : 0.0; }
  /// Nearest-rank q-quantile (0 <= q <= 1) of the window; 0 without samples.
  double percentileMs(double q) const;

 private:
  size_t window_;
  std::vector<double> recent_ms_;  ///< ring buffer of the last `window_` samples
  size_t next_ = 0;
  uint64_t count_ = 0;
  double sum_ms_ = 0.0;
  double last_ms_ = 0.0;
};

}  // namespace fragg::ros
