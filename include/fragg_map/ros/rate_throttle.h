// When the map server may publish its next update of a throttled output: at most `rate_hz`
// updates per second (0 = no limit). Used for the marker topics (`marker_rate`) and the
// whole-map outputs (`map_rate`). The caller supplies the time (seconds of a steady clock), so
// the rule is testable without ROS. What is not published stays pending: the markers of the
// blocks changed since the last update are built from BlockMeta::changed_at at the next one,
// and MapOutputCache catches up from the revision it last saw.
#pragma once

#include <algorithm>

#include "fragg_map/errors.h"

namespace fragg::ros {

class RateThrottle {
 public:
  explicit RateThrottle(double rate_hz) : period_s_(rate_hz > 0.0 ? 1.0 / rate_hz : 0.0) {
    if (!(rate_hz >= 0.0)) throw fragg::InvalidArgument("an output rate must be >= 0 Hz");
  }

  /// Seconds between updates; 0 without a limit.
  double periodS() const { return period_s_; }
  bool limited() const { return period_s_ > 0.0; }
  /// How often a timer looks for pending updates (those held back while the input flowed):
  /// every 0.1 s, or every period when that is shorter, so that a pending update goes out at
  /// most that long after it is due (within a period + 0.1 s of the last change).
  double flushTickS() const { return std::min(period_s_, kMaxFlushTickS); }

  /// Whether an update may go out at `now_s`: always without a limit or before the first one,
  /// else once a period has passed since the last.
  bool due(double now_s) const { return !limited() || !published_ || now_s - last_s_ >= period_s_; }

  /// An update went out at `now_s`.
  void published(double now_s) {
    last_s_ = now_s;
    published_ = true;
  }

 private:
  static constexpr double kMaxFlushTickS = 0.1;
  double period_s_;
  double last_s_ = 0.0;
  bool published_ = false;
};

/// A whole-map output under a RateThrottle that holds back what is not due: whether an update
/// is held back, and the stamp it is to carry (that of the last input it covers).
template <class Stamp>
class HeldBackUpdate {
 public:
  explicit HeldBackUpdate(double rate_hz) : throttle_(rate_hz) {}
  const RateThrottle& throttle() const { return throttle_; }

  /// After an input stamped `stamp` at `now_s`: true when the update may go out now, else it
  /// is held back with that stamp.
  bool letThrough(double now_s, const Stamp& stamp) {
    if (throttle_.due(now_s)) return true;
    pending_ = true;
    stamp_ = stamp;
    return false;
  }
  /// An update went out at `now_s`: nothing is held back.
  void published(double now_s) {
    throttle_.published(now_s);
    pending_ = false;
  }
  /// Nothing to hold back (no subscriber: a later one gets the map when it connects).
  void drop() { pending_ = false; }
  /// Whether a timer should send the held-back update at `now_s`.
  bool flushDue(double now_s) const { return pending_ && throttle_.due(now_s); }
  const Stamp& pendingStamp() const { return stamp_; }

 private:
  RateThrottle throttle_;
  bool pending_ = false;
  Stamp stamp_{};
};

}  // namespace fragg::ros
