// What a steady timer runs to send an update the rate limits held back (marker_rate,
// map_rate): it never waits. When the publisher's mutex or the map is busy it does nothing:
// whoever holds the mutex is publishing already, a writer of the map publishes after its edit,
// and the next tick comes within 0.1 s.
#pragma once

#include <ros/console.h>

#include <exception>
#include <mutex>
#include <optional>

#include "shared_map.h"

namespace fragg::ros {

/// Under `publish_mutex` (tried, not waited for): when `ready()` says there is something to
/// send, `publish(map)` under the map's read lock (tried too). A failure is logged, not thrown
/// into the timer.
template <class Ready, class Publish>
void flushWithoutWaiting(std::mutex& publish_mutex, SharedMap& shared, Ready&& ready,
                         Publish&& publish) {
  std::unique_lock<std::mutex> publishing(publish_mutex, std::try_to_lock);
  if (!publishing.owns_lock() || !ready()) return;
  // Named in the insertion's lock-holder trace: the node's one read lock without a name, so
  // most likely the "a reader" that 40 insertions waited for in an H100 run (2026-12-08).
  const std::optional<SharedMap::ReadGuard> state = shared.tryRead("outputs' timer flush");
  if (!state) return;
  try {
    publish((*state)->map);
  } catch (const std::exception& e) {
    ROS_ERROR_THROTTLE(5.0, "fragg_map: publishing failed: %s", e.what());
  }
}

}  // namespace fragg::ros
