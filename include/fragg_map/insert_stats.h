// What one insertion did, for logs, the CLI summary and the ROS stats topic.
#pragma once

#include <cstdint>

#include "fragg_map/culling.h"
#include "fragg_map/sensor_model.h"

namespace fragg {

struct InsertStats {
  uint64_t scan_id = 0;  ///< the scan's insertion index (not summed by add())
  /// The sensor model the scan was integrated with: an `auto` model resolved for the cloud,
  /// max range set (not summed by add()).
  SensorModel sensor;
  uint64_t points_in = 0;       ///< points given
  uint64_t rays_hit = 0;        ///< rays ending in a hit
  uint64_t rays_free_only = 0;  ///< beyond max range: clear up to max range, no hit
  uint64_t rays_no_return = 0;  ///< organised no-return rays cleared (when enabled)
  /// MapParams::dynamic: hits in void space, classified dynamic and not inserted (their rays
  /// cleared up to them); not counted in rays_hit
  uint64_t rays_dynamic = 0;
  /// NaN / Inf / (0, 0, 0), beyond the int32 key range, or ending more than 2^24 voxels from the
  /// sensor (kMaxRayV: beyond float precision)
  uint64_t dropped_invalid = 0;
  uint64_t dropped_min_range = 0;        ///< closer than min range
  uint64_t dropped_outside_frustum = 0;  ///< outside an explicit sensor model's frustum
  uint64_t dropped_height = 0;           ///< map-frame z outside MapParams::height_filter
  uint64_t voxel_visits = 0;             ///< cells visited by the traversal (with repeats)
  uint64_t cells_updated = 0;            ///< cells whose log-odds were updated (once per scan)
  uint64_t blocks_touched = 0;
  uint64_t blocks_created = 0;
  uint64_t blocks_uploaded = 0;  ///< CUDA: host blocks copied to the device for this scan
  uint64_t blocks_evicted = 0;   ///< CUDA: device slots given back to make room
  /// CUDA: 1 when the scan's points went up while the device worked on the update before
  /// (UpdateSettings::stage_next: Map::insertSequence, Map::correctPoses).
  uint64_t scans_staged = 0;
  /// CUDA: ray passes (and dynamic classification passes) run again after one stopped on a
  /// block it lacked (host-only, or in a paged-out region) or on a full pool / budget, and the
  /// time from the end of the scan's first pass to the end of its last (the stops' uploads and
  /// paging included).
  uint64_t passes_redone = 0;
  double seconds_redone = 0;
  CullCounters culling;
  double seconds_total = 0;
  double seconds_prepare = 0;    ///< transform + filter (+ dynamic classification)
  double seconds_cull = 0;       ///< sensor model (auto), frustum and host culling
  double seconds_residency = 0;  ///< CUDA: window, uploads, evictions (host side)
  double seconds_raycast = 0;
  double seconds_apply = 0;

  void add(const InsertStats& o);
};

}  // namespace fragg
