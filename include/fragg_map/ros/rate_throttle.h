// When the map server may publish its next marker update: at most `rate_hz` updates per
// second (0 = no limit). The caller supplies the time (seconds of a steady clock), so the rule
// is testable without ROS. What is not published stays pending: the markers of the blocks
// changed since the last update are built from BlockMeta::changed_at at the next one.
#pragma once

#include "fragg_map/errors.h"

namespace fragg::ros {

class MarkerThrottle {
 public:
  explicit MarkerThrottle(double rate_hz) : period_s_(rate_hz > 0.0 ? 1.0 / rate_hz : 0.0) {
    if (!(rate_hz >= 0.0)) throw fragg::InvalidArgument("marker rate must be >= 0 Hz");
  }

  /// Seconds between updates; 0 without a limit.
  double periodS() const { return period_s_; }
  bool limited() const { return period_s_ > 0.0; }

  /// Whether an update may go out at `now_s`: always without a limit or before the first one,
  /// else once a period has passed since the last.
  bool due(double now_s) const { return !limited() || !published_ || now_s - last_s_ >= period_s_; }

  /// An update went out at `now_s`.
  void published(double now_s) {
    last_s_ = now_s;
    published_ = true;
  }

 private:
  double period_s_;
  double last_s_ = 0.0;
  bool published_ = false;
};

}  // namespace fragg::ros
