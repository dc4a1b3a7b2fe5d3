// Counters of the map server (clouds inserted, dropped and why, insertion, correction and
// collision-check times, frontier queries and topic updates), safe to update from the insertion
// thread and read from service and publisher threads.
#pragma once

#include <cstdint>
#include <mutex>
#include <string>

#include "fragg_map/MapStats.h"
#include "fragg_map/map.h"
#include "fragg_map/ros/timing_stats.h"

namespace fragg::ros {

class ServerStats {
 public:
  void addInsertion(uint64_t points, double ms);
  void addDroppedNoTf();
  void addDroppedQueueFull();
  void addRejected();
  /// A pose correction that moved `scans` kept scans in `ms`.
  void addCorrection(uint64_t scans, double ms);
  /// A ~check_collision call that checked `poses` poses in `ms`.
  void addCollisionCheck(uint64_t poses, double ms);
  /// A ~get_frontiers call answered.
  void addFrontierQuery();
  /// An update of the frontier topics (these counters run from start; ~reset keeps them).
  void addFrontierUpdate(bool full, uint64_t blocks_examined, uint64_t cells, double ms);
  /// Forgets the insertions, corrections and collision checks (after ~reset); the drop
  /// counters keep counting.
  void clearInsertions();
  /// Every counter back to zero, drops included, with `scans` clouds in the map (after ~reset:
  /// 0; after ~load_map or the start-up map: the file's count).
  void restart(uint64_t scans);

  /// The statistics message; `map` must be locked by the caller.
  fragg_map::MapStats toMsg(const fragg::Map& map, const std::string& frame_id,
                            const ::ros::Time& stamp) const;
  uint64_t droppedNoTf() const;

 private:
  mutable std::mutex mutex_;
  uint64_t scans_ = 0;
  uint64_t points_ = 0;
  uint64_t dropped_no_tf_ = 0;
  uint64_t dropped_queue_full_ = 0;
  uint64_t rejected_ = 0;
  TimingStats insertion_ms_;
  uint64_t corrections_ = 0;
  uint64_t corrected_scans_ = 0;
  double correction_ms_last_ = 0.0;
  TimingStats collision_ms_{1};  // last and mean only (no percentile is published)
  uint64_t collision_poses_ = 0;
  uint64_t frontier_queries_ = 0;
  uint64_t frontier_updates_ = 0;
  bool frontier_update_full_ = false;
  uint64_t frontier_blocks_examined_ = 0;
  uint64_t frontier_cells_ = 0;
  double frontier_ms_last_ = 0.0;
};

}  // namespace fragg::ros
