// ~check_collision: a shape checked against the map at poses, or along the path through them
// (fragg_map/planning: checkPoses, checkPath on the CPU) on a copy of the cells the shape can
// reach, taken under the map's read lock (the checks run without it, on a thread of the
// service's own: service_threads.h). Poses come
// through tf into the map frame; the request's options or the collision/* parameters apply.
// After each answered call the `collisions` topic shows the shape at the checked poses
// (collision_markers.h). Bad arguments (no poses, NaN, a quaternion off unit, a shape the core
// refuses, a missing transform, no mesh) answer success=false with the reason.
#pragma once

#include <ros/node_handle.h>
#include <ros/publisher.h>
#include <ros/service_server.h>
#include <tf2_ros/buffer.h>

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "fragg_map/CheckCollision.h"
#include "fragg_map/planning/collision_shape.h"
#include "fragg_map/ros/server_params.h"
#include "server_stats.h"
#include "shared_map.h"

namespace fragg::ros {

class CollisionService {
 public:
  /// Reads the collision/mesh OBJ when it is set: throws fragg::IoError or
  /// fragg::InvalidArgument naming the parameter when it cannot be used.
  CollisionService(::ros::NodeHandle& nh, ::ros::NodeHandle& private_nh, const ServerParams& params,
                   const tf2_ros::Buffer& tf, SharedMap* shared, ServerStats* stats);

 private:
  bool check(fragg_map::CheckCollision::Request& req, fragg_map::CheckCollision::Response& res);
  /// The request's poses as T_map_shape, each checked; throws fragg::InvalidArgument naming the
  /// pose for a bad value or a missing transform.
  std::vector<Eigen::Isometry3d> posesInMap(const fragg_map::CheckCollision::Request& req) const;
  Eigen::Isometry3d mapFromFrame(const std::string& frame, const ::ros::Time& stamp) const;

  const ServerParams params_;
  const tf2_ros::Buffer& tf_;
  SharedMap* shared_;
  ServerStats* stats_;
  std::optional<planning::CollisionShape> configured_mesh_;  ///< collision/mesh
  ::ros::Publisher markers_pub_;
  ::ros::ServiceServer service_;
};

}  // namespace fragg::ros
