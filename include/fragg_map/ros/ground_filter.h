// octomap_server's filter_ground: the ground plane of a cloud, found in the robot's base frame
// with PCL's RANSAC plane segmentation, its points marked free-only (PointCloud::free_only):
// the map clears the rays to them and leaves their own cells as they were, as octomap_server
// inserts ground points.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>

#include "fragg_map/point_cloud.h"

namespace fragg::ros {

/// octomap_server's ground_filter/* parameters.
struct GroundFilterParams {
  double distance_m = 0.04;        ///< ground_filter/distance: RANSAC inlier distance to a plane
  double angle_rad = 0.15;         ///< ground_filter/angle: plane normal at most this far from z
  double plane_distance_m = 0.07;  ///< ground_filter/plane_distance: the plane's |d| below this
};

struct GroundSplit {
  size_t points = 0;         ///< finite, non-zero points considered
  size_t ground = 0;         ///< of those, marked free-only
  size_t other_planes = 0;   ///< horizontal planes found farther than plane_distance from z = 0
  bool plane_found = false;  ///< false: no plane (fallback by height) or under 50 points
};

/// As octomap_server's filterGroundPlane, on the finite non-zero points of `cloud` (sensor
/// frame) moved to the base frame by T_base_sensor: clouds of fewer than 50 such points have
/// no ground; otherwise planes perpendicular to z (within angle_rad) are sought with RANSAC
/// (200 iterations, inliers within distance_m, coefficients refined) until one lies within
/// plane_distance_m of z = 0 (its inliers are ground) or fewer than 11 points remain, planes
/// farther away being taken out (not ground) one by one; when none is found, the points with
/// |z_base| <= plane_distance_m are ground. Sets cloud->free_only (one flag a point; other
/// flags already set stay set). Deterministic (PCL's fixed RANSAC seed).
GroundSplit markGroundPoints(const Eigen::Isometry3d& T_base_sensor,
                             const GroundFilterParams& params, PointCloud* cloud);

}  // namespace fragg::ros
