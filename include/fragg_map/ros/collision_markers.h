// The answer of a collision check as a visualization_msgs/MarkerArray (the server's
// `collisions` topic): the shape at every colliding pose in red (ns "colliding"), at free poses
// in translucent green (ns "free"), and in path mode the line through the poses (ns "path") and
// the first colliding interpolated pose in red (ns "path_hit"). The array starts with a
// DELETEALL, so each call replaces the previous one. Box, sphere and capsule are drawn as
// rviz primitives (a capsule as a cylinder and two spheres), a mesh as a TRIANGLE_LIST.
#pragma once

#include <ros/time.h>
#include <visualization_msgs/MarkerArray.h>

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "fragg_map/planning/collision_shape.h"

namespace fragg::ros {

struct CollisionMarkerInput {
  const planning::CollisionShape* shape = nullptr;
  const std::vector<Eigen::Isometry3d>* T_map_shape = nullptr;  ///< the checked poses
  const std::vector<bool>* collides = nullptr;                  ///< one flag per pose
  bool path_mode = false;
  std::optional<Eigen::Isometry3d> T_map_path_hit;  ///< the path's first colliding pose
};

/// At most `max_poses` poses are drawn: the colliding ones first (in order), then free ones.
/// Throws fragg::InvalidArgument when the flags do not match the poses.
visualization_msgs::MarkerArray collisionMarkers(const CollisionMarkerInput& in,
                                                 const std::string& frame_id,
                                                 const ::ros::Time& stamp, size_t max_poses);

}  // namespace fragg::ros
