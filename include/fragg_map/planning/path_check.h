// Path mode: a shape moved along consecutive waypoints (T_map_shape), checked at interpolated
// poses: translation linear, rotation by slerp, steps of at most max_translation_step_m and
// max_rotation_step_rad; the first colliding pose is reported as a waypoint index and a
// fraction along the segment that starts there.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "fragg_map/planning/collision_check.h"

namespace fragg::planning {

struct PathOptions {
  double max_translation_step_m = 0.0;  ///< <= 0: half a voxel of the map
  double max_rotation_step_rad = 0.05;  ///< > 0
};

struct PathResult {
  bool collides = false;
  /// Segment of the first collision: it starts at waypoint first_segment (-1: none). A
  /// collision at waypoint 0 itself is segment 0, fraction 0; with one waypoint, the only
  /// pose is segment 0.
  int64_t first_segment = -1;
  double fraction = 0.0;  ///< along that segment, in [0, 1]
  Eigen::Isometry3d T_map_shape_hit = Eigen::Isometry3d::Identity();  ///< the colliding pose
  CollisionResult hit;                                                ///< that pose's result
  uint64_t poses_checked = 0;  ///< interpolated poses checked (the waypoints included)
};

/// Interpolation runs on the host; the poses are checked in batches on `backend`.
/// Throws InvalidArgument for an empty path, a bad pose, bad options or step limits.
PathResult checkPath(const Map& map, const CollisionShape& shape,
                     const std::vector<Eigen::Isometry3d>& waypoints_T_map_shape,
                     const CollisionOptions& options, const PathOptions& path = PathOptions(),
                     Backend backend = Backend::kCpu);

}  // namespace fragg::planning
