// The parameters the map server changes while it runs through dynamic_reconfigure
// (cfg/MapServer.cfg: octomap_server's names), as plain values: what the server's parameters
// give them at start-up, and the server's parameters with them applied (the start-up checks).
#pragma once

#include "fragg_map/ros/server_params.h"

namespace fragg::ros {

/// A height at or beyond this magnitude (m) means "no limit" in occupancy_min_z/max_z
/// (dynamic_reconfigure has no infinity; the cfg's range ends here).
constexpr double kReconfigureNoHeightLimitM = 1000.0;

/// cfg/MapServer.cfg's fields.
struct ReconfigurableParams {
  bool compress_map = true;
  bool incremental_2D_projection = false;
  bool filter_speckles = false;
  double occupancy_min_z_m = -kReconfigureNoHeightLimitM;
  double occupancy_max_z_m = kReconfigureNoHeightLimitM;
  double sensor_model_max_range_m = ServerParams::kDefaultMaxRangeM;  ///< <= 0: no limit
  double sensor_model_min_range_m = 0.0;                              ///< < 0 reads as 0
  bool filter_ground = false;
  double ground_filter_distance_m = 0.04;
  double ground_filter_angle_rad = 0.15;
  double ground_filter_plane_distance_m = 0.07;
};

/// The values `p` holds (an unlimited height as -/+kReconfigureNoHeightLimitM).
[[nodiscard]] ReconfigurableParams reconfigurableOf(const ServerParams& p);

/// `p` with `v` applied; throws fragg::InvalidArgument naming the first bad value (a height band
/// whose minimum lies above its maximum, a ground filter value out of range, a bad range).
[[nodiscard]] ServerParams withReconfigured(const ServerParams& p, const ReconfigurableParams& v);

}  // namespace fragg::ros
