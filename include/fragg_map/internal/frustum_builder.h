// Builds the map-frame frustum of a resolved (non-auto) sensor model at a pose.
#pragma once

#include <Eigen/Geometry>

#include "fragg_map/frustum.h"
#include "fragg_map/sensor_model.h"

namespace fragg {

/// Pinhole: near plane (through the origin, test 0), four side planes, the range sphere.
/// LiDAR: the range sphere and the elevation cones that apply. `model.max_range_m` must be > 0.
Frustum buildFrustum(const SensorModel& model, const Eigen::Isometry3d& T_map_sensor,
                     double resolution_m);

}  // namespace fragg
