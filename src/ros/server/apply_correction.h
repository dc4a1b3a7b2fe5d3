// The step ~correct_poses and corrected_path share: a correction plan through
// fragg::Map::correctPoses, timed and counted.
#pragma once

#include <chrono>

#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "fragg_map/ros/pose_correction.h"
#include "server_stats.h"

namespace fragg::ros {

/// Wall time of the correction [ms]; nothing happens (0 ms) for an empty plan. The caller
/// holds the map's write lock. Throws fragg::InvalidArgument when the map keeps no scans.
inline double applyCorrection(const CorrectionPlan& plan, fragg::Map* map, ServerStats* stats) {
  if (plan.T_map_sensor_new.empty()) return 0.0;
  const auto start = std::chrono::steady_clock::now();
  map->correctPoses(plan.T_map_sensor_new);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  stats->addCorrection(plan.T_map_sensor_new.size(), ms);
  return ms;
}

/// Refuses a correction on a server that keeps no scans.
inline void requireKeptScans(const fragg::Map& map) {
  if (!map.params().scans.keep && map.scanStore().size() == 0)
    throw fragg::InvalidArgument(
        "this map keeps no scans (parameter keep_scans is false, or the loaded map was saved "
        "without them)");
}

}  // namespace fragg::ros
