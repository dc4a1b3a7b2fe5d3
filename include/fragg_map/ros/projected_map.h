// fragg::Map -> nav_msgs/OccupancyGrid: the map projected onto the xy plane between two
// heights (octomap_server's projected_map).
#pragma once

#include <nav_msgs/OccupancyGrid.h>
#include <ros/time.h>

#include <cstdint>
#include <string>

#include "fragg_map/map.h"

namespace fragg::ros {

/// OccupancyGrid cell values of projected_map (nav_msgs' convention).
namespace grid_value {
constexpr int8_t kUnknown = -1;
constexpr int8_t kFree = 0;
constexpr int8_t kOccupied = 100;
}  // namespace grid_value

/// One axis of a projected map's grid: inclusive voxel keys.
struct GridSpan {
  int64_t lo = 0, hi = -1;
};

/// The span octomap_server gives its projected_map (handlePreNodeTraversal with the default
/// zero padding, full depth) on one axis for a map whose observed cells span keys [lo, hi]:
/// the keys of the faces liboctomap's getMetricMin/Max computes, in its arithmetic (double
/// faces keyed as a float point3d: the upper face's key is often one beyond hi, a lower face
/// at a negative coordinate can key to lo - 1), widened to take in the origin's cell.
GridSpan octomapServerGridSpan(int64_t lo, int64_t hi, double resolution_m);

/// With `hide_speckles` (filter_speckles) an occupied cell without an occupied neighbour
/// counts neither as occupied nor as free.
/// One grid cell per voxel column (the map's resolution), covering the xy bounds of the
/// observed map. A column is 100 (occupied) when a voxel whose cube overlaps the open band
/// (min_z_m, max_z_m) is occupied (octomap_server's rule, height_band.h), 0 (free) when such a
/// voxel is free and none is occupied, -1 (unknown) otherwise; infinite limits leave that side
/// open. With `octomap_bounds` the grid spans octomapServerGridSpan of those bounds (the
/// columns added are unknown). An empty map gives a 0 x 0
/// grid. Throws fragg::InvalidArgument for NaN heights or min_z_m > max_z_m.
nav_msgs::OccupancyGrid projectedMap(const fragg::Map& map, double min_z_m, double max_z_m,
                                     const std::string& frame_id, const ::ros::Time& stamp,
                                     bool hide_speckles = false, bool octomap_bounds = false);

}  // namespace fragg::ros
