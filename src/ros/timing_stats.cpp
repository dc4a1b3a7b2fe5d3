// Insertion timing statistics (mean over all, p99 over a ring buffer).
#include "fragg_map/ros/timing_stats.h"

#include <algorithm>
#include <cmath>

#include "fragg_map/errors.h"

namespace fragg::ros {

TimingStats::TimingStats(size_t window) : window_(window) {
  if (window_ == 0) throw fragg::InvalidArgument("timing window must be >= 1 sample");
  recent_ms_.reserve(std::min<size_t>(window_, 1024));
}

void TimingStats::add(double ms) {
  if (recent_ms_.size() < window_)
    recent_ms_.push_back(ms);
  else
    recent_ms_[next_] = ms;
  next_ = (next_ + 1) % window_;
  ++count_;
  sum_ms_ += ms;
  last_ms_ = ms;
}

void TimingStats::clear() {
  recent_ms_.clear();
  next_ = 0;
  count_ = 0;
  sum_ms_ = 0.0;
  last_ms_ = 0.0;
}

double TimingStats::percentileMs(double q) const {
  if (recent_ms_.empty()) return 0.0;
  std::vector<double> sorted = recent_ms_;
  std::sort(sorted.begin(), sorted.end());
  const size_t rank = static_cast<size_t>(std::ceil(std::clamp(q, 0.0, 1.0) * sorted.size()));
  return sorted[std::min(sorted.size() - 1, rank == 0 ? 0 : rank - 1)];
}

}  // namespace fragg::ros
