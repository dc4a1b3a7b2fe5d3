// ~check_collision: validate, transform, copy the reachable cells under the read lock, check
// the copy, answer, draw.
#include "collision_service.h"

#include <ros/console.h>
#include <tf2/exceptions.h>
#include <tf2_eigen/tf2_eigen.h>
#include <visualization_msgs/MarkerArray.h>

#include <chrono>
#include <cmath>
#include <optional>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/geometry/obj_file.h"
#include "fragg_map/planning/collision_check.h"
#include "fragg_map/planning/path_check.h"
#include "fragg_map/ros/collision_markers.h"
#include "fragg_map/ros/collision_shape_msg.h"
#include "fragg_map/ros/pose_correction.h"
#include "frame_text.h"

namespace fragg::ros {
namespace {

void clearAnswer(fragg_map::CheckCollision::Response& res) {
  res = fragg_map::CheckCollision::Response();
  res.first_collision = -1;
  res.path_first_segment = -1;
}

// The observed cells of `map` a shape can overlap at any of the poses, or on the straight
// segments between them: every cell whose centre lies in the poses' box grown by the shape's
// bounding radius, sqrt(3) margins and two cells (a cell the grown shape overlaps has its
// centre within half a cell diagonal of it), as Map::extract copies them (exact cells, so
// checks on the copy answer as on the map). Hold the map's read lock.
Map reachableCopy(const Map& map, const planning::CollisionShape& shape,
                  const std::vector<Eigen::Isometry3d>& T_map_shape, double margin_m) {
  Eigen::Vector3d lo = T_map_shape.front().translation(), hi = lo;
  for (const Eigen::Isometry3d& T : T_map_shape) {
    lo = lo.cwiseMin(T.translation());
    hi = hi.cwiseMax(T.translation());
  }
  const double grow = shape.boundingRadius() + std::sqrt(3.0) * margin_m + 2.0 * map.resolution();
  return map.extract(lo.array() - grow, hi.array() + grow);
}

}  // namespace

CollisionService::CollisionService(::ros::NodeHandle& nh, ::ros::NodeHandle& private_nh,
                                   const ServerParams& params, const tf2_ros::Buffer& tf,
                                   SharedMap* shared, ServerStats* stats)
    : params_(params), tf_(tf), shared_(shared), stats_(stats) {
  const CollisionParams& c = params_.collision;
  if (!c.mesh.empty()) {
    try {
      configured_mesh_ = planning::CollisionShape::mesh(geometry::readObj(c.mesh), c.mesh_scale);
    } catch (const std::exception& e) {
      throw fragg::InvalidArgument("parameter 'collision/mesh': " + std::string(e.what()));
    }
    ROS_INFO("fragg_map: collision mesh %s (%s)", c.mesh.c_str(),
             configured_mesh_->describe().c_str());
  }
  markers_pub_ = nh.advertise<visualization_msgs::MarkerArray>("collisions", 1, params_.latch);
  service_ = private_nh.advertiseService("check_collision", &CollisionService::check, this);
}

Eigen::Isometry3d CollisionService::mapFromFrame(const std::string& frame_in,
                                                 const ::ros::Time& stamp) const {
  const std::string frame = withoutLeadingSlash(frame_in);
  if (frame.empty() || frame == params_.frame_id) return Eigen::Isometry3d::Identity();
  std::string error;
  try {
    if (tf_.canTransform(params_.frame_id, frame, stamp, &error))
      return tf2::transformToEigen(tf_.lookupTransform(params_.frame_id, frame, stamp));
  } catch (const tf2::TransformException& e) {
    error = e.what();
  }
  throw fragg::InvalidArgument("no transform from '" + frame + "' to '" + params_.frame_id +
                               "' at t=" + std::to_string(stamp.toSec()) + ": " + error);
}

std::vector<Eigen::Isometry3d> CollisionService::posesInMap(
    const fragg_map::CheckCollision::Request& req) const {
  const bool by_poses = !req.poses.empty(), by_path = !req.path.poses.empty();
  if (by_poses && by_path) throw fragg::InvalidArgument("give poses or path, not both");
  if (!by_poses && !by_path) throw fragg::InvalidArgument("no poses given (poses and path empty)");
  const std::vector<geometry_msgs::PoseStamped>& in = by_poses ? req.poses : req.path.poses;
  std::vector<Eigen::Isometry3d> out;
  out.reserve(in.size());
  for (size_t i = 0; i < in.size(); ++i) {
    // A path pose without a frame of its own is in the path's frame at the path's stamp.
    const std_msgs::Header& header =
        by_path && in[i].header.frame_id.empty() ? req.path.header : in[i].header;
    try {
      const Eigen::Isometry3d T_frame_shape = isometryFromPose(in[i].pose);
      out.push_back(mapFromFrame(header.frame_id, header.stamp) * T_frame_shape);
    } catch (const fragg::InvalidArgument& e) {
      throw fragg::InvalidArgument("pose " + std::to_string(i) + ": " + e.what());
    }
  }
  return out;
}

bool CollisionService::check(fragg_map::CheckCollision::Request& req,
                             fragg_map::CheckCollision::Response& res) {
  clearAnswer(res);
  try {
    planning::CollisionOptions options;
    options.unknown_is_occupied = req.override_options ? static_cast<bool>(req.unknown_is_occupied)
                                                       : params_.collision.unknown_is_occupied;
    options.margin_m = req.override_options ? req.margin : params_.collision.margin_m;
    options.count_cells = req.count_cells;
    planning::validate(options);
    const planning::CollisionShape shape =
        shapeFromRequest(req.shape, req.dimensions, req.mesh, configured_mesh_);
    const std::vector<Eigen::Isometry3d> poses = posesInMap(req);

    const auto t0 = std::chrono::steady_clock::now();
    std::vector<planning::CollisionResult> results;
    std::optional<planning::PathResult> path;
    {
      // The cells the shape can reach at any pose (and along the path between them), copied
      // under the read lock; the checks run on the copy without it, so that a large batch
      // holds neither insertion nor the other services back.
      std::optional<Map> reach;
      {
        const SharedMap::ReadGuard state = shared_->read("~check_collision");
        reach.emplace(reachableCopy(state->map, shape, poses, options.margin_m));
      }
      results = planning::checkPoses(*reach, shape, poses, options);
      if (req.path_mode) path = planning::checkPath(*reach, shape, poses, options);
      for (size_t i = 0; i < results.size(); ++i) {
        if (!results[i].collides) continue;
        const Eigen::Vector3d c = reach->centerOf(results[i].first_cell);
        res.first_cell.x = c.x();
        res.first_cell.y = c.y();
        res.first_cell.z = c.z();
        break;
      }
    }
    res.ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

    std::vector<bool> collides(results.size());
    for (size_t i = 0; i < results.size(); ++i) {
      collides[i] = results[i].collides;
      res.collides.push_back(results[i].collides);
      if (req.count_cells) res.colliding_cells.push_back(results[i].colliding_cells);
      if (!results[i].collides) continue;
      ++res.colliding;
      if (res.first_collision < 0) res.first_collision = static_cast<int64_t>(i);
    }
    if (path) {
      res.path_collides = path->collides;
      res.path_first_segment = path->first_segment;
      res.path_fraction = path->fraction;
      res.path_poses_checked = path->poses_checked;
    }
    res.success = true;
    res.message = std::to_string(res.colliding) + " of " + std::to_string(poses.size()) +
                  " poses collide (" + shape.describe() + ")";
    if (path)
      res.message += path->collides
                         ? "; the path collides on segment " + std::to_string(path->first_segment) +
                               " at " + std::to_string(path->fraction)
                         : "; the path is clear";
    stats_->addCollisionCheck(poses.size(), res.ms);

    if (markers_pub_ && (params_.latch || markers_pub_.getNumSubscribers() > 0)) {
      CollisionMarkerInput in;
      in.shape = &shape;
      in.T_map_shape = &poses;
      in.collides = &collides;
      in.path_mode = req.path_mode;
      if (path && path->collides) in.T_map_path_hit = path->T_map_shape_hit;
      markers_pub_.publish(collisionMarkers(in, params_.frame_id, ::ros::Time::now(),
                                            static_cast<size_t>(params_.collision.max_markers)));
    }
  } catch (const std::exception& e) {
    clearAnswer(res);
    res.success = false;
    res.message = e.what();
    ROS_WARN_THROTTLE(1.0, "fragg_map: check_collision refused: %s", e.what());
  }
  return true;
}

}  // namespace fragg::ros
