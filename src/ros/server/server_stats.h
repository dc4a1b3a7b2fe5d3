// Counters of the map server (clouds inserted, dropped and why (CloudFault), points left out
// and why, insertion, correction and
// collision-check times, frontier queries and topic updates), safe to update from the insertion
// thread and read from service and publisher threads.
#pragma once

#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

#include "fragg_map/MapStats.h"
#include "fragg_map/insert_stats.h"
#include "fragg_map/map.h"
#include "fragg_map/ros/mask_mirror.h"
#include "fragg_map/ros/timing_stats.h"

namespace fragg::ros {

/// Why a cloud did not reach the map (one counter each in ~stats).
enum class CloudFault {
  kMalformed,      ///< PointCloud2 layout: fields, sizes (an empty cloud is not a fault)
  kNoFinitePoint,  ///< every point NaN / Inf or beyond the map's key range
  kBadTransform,   ///< the transform to the map frame not finite, not rigid or out of range
  kInsertFailed,   ///< the map threw while inserting (the scan is not in the map)
  kTfTooOld,       ///< stamp older than the tf buffer holds: dropped without waiting
};

/// Every cloud received lands in exactly one of: inserted, a drop (queue, no_tf, tf_too_old),
/// a rejection or insertion failure (CloudFault), empty; until then it is in flight. The
/// outcome methods below take it out of flight; the counters restart together (restart()), the
/// clouds in flight then counted as received anew, so that at every moment
/// clouds_received = clouds_inserted + dropped_clouds + empty_clouds + clouds_in_flight.
class ServerStats {
 public:
  /// A cloud taken from cloud_in (before the queue): received and in flight.
  void addReceived();
  /// The latency of an inserted cloud and its parts (cloud_trace.h).
  void addLatency(double queue_ms, double tf_ms, double publish_ms, double total_ms);
  /// A scan inserted: its points, wall time and the map's per-point counts.
  void addInsertion(uint64_t points, double ms, const fragg::InsertStats& inserted = {});
  void addDroppedNoTf();
  void addDroppedQueueFull();
  /// A cloud of 0 points (drivers publish them): skipped, counted, not a fault.
  void addEmptyCloud();
  void addFault(CloudFault fault);
  /// Points left out before insertion (beyond the map's key range): added to points_invalid.
  void addPointsInvalid(uint64_t points);
  /// The CUDA backend ran out of device memory and the map went on with the CPU backend.
  void addBackendFallback();
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

  /// How toMsg fills the map's size figures (known voxels, blocks, bytes: Map::memory() walks
  /// every cell, and on a device backend writes its blocks back first).
  enum class MapFigures {
    kExact,   ///< computed now (~get_stats)
    kRecent,  ///< computed at most every kMapFiguresPeriodSeconds, else the last ones (~stats)
  };
  static constexpr double kMapFiguresPeriodSeconds = 5.0;

  /// The statistics message; `map` must be locked by the caller. kRecent with `mirror` (the
  /// outputs' mask mirror of a CUDA map, synced at their take-ins): blocks and known voxels
  /// from it (cells free or occupied; kept as they change) and the bytes from
  /// Map::memoryAsHeld, so that ~stats neither writes the device's blocks back nor walks the
  /// cells.
  fragg_map::MapStats toMsg(const fragg::Map& map, const std::string& frame_id,
                            const ::ros::Time& stamp, MapFigures figures = MapFigures::kExact,
                            const MaskMirror* mirror = nullptr) const;
  uint64_t droppedNoTf() const;
  uint64_t faults(CloudFault fault) const;

 private:
  mutable std::mutex mutex_;
  /// One cloud out of flight (an outcome counted); the caller holds mutex_.
  void settle();

  /// The last Map::memory() (kRecent): when and at which map revision it was taken.
  mutable std::mutex memory_mutex_;
  mutable fragg::MemoryStats memory_;
  mutable bool memory_valid_ = false;
  mutable uint64_t memory_revision_ = 0;
  mutable std::chrono::steady_clock::time_point memory_at_;

  uint64_t scans_ = 0;
  uint64_t points_ = 0;
  uint64_t received_ = 0;   ///< clouds received since the counters restarted
  uint64_t inserted_ = 0;   ///< of them inserted (scans_ also counts a loaded map's)
  uint64_t in_flight_ = 0;  ///< received, no outcome yet (queued, waiting for tf, inserting)
  uint64_t dropped_no_tf_ = 0;
  uint64_t dropped_queue_full_ = 0;
  uint64_t empty_clouds_ = 0;
  uint64_t faults_[5] = {0, 0, 0, 0, 0};  // by CloudFault
  uint64_t backend_fallbacks_ = 0;
  uint64_t points_invalid_ = 0;
  uint64_t points_beyond_range_ = 0;
  uint64_t points_below_min_range_ = 0;
  uint64_t points_outside_height_ = 0;
  uint64_t points_outside_frustum_ = 0;
  TimingStats insertion_ms_;
  TimingStats latency_ms_, queue_ms_, tf_ms_, publish_ms_;
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
