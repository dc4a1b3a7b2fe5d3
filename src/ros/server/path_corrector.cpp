// corrected_path -> sensor poses of kept scans -> one Map::correctPoses batch.
#include "path_corrector.h"

#include <ros/console.h>
#include <tf2/exceptions.h>
#include <tf2_eigen/tf2_eigen.h>

#include <cmath>
#include <string>
#include <vector>

#include "apply_correction.h"
#include "fragg_map/errors.h"
#include "fragg_map/ros/pose_correction.h"
#include "frame_text.h"

namespace fragg::ros {

PathCorrector::PathCorrector(::ros::NodeHandle& nh, const ServerParams& params,
                             const tf2_ros::Buffer& tf, SharedMap* shared, ServerStats* stats,
                             std::function<void()> on_corrected)
    : params_(params),
      tf_(tf),
      shared_(shared),
      stats_(stats),
      on_corrected_(std::move(on_corrected)) {
  sub_ = nh.subscribe("corrected_path", 2, &PathCorrector::onPath, this);
}

void PathCorrector::onPath(const nav_msgs::Path::ConstPtr& path) {
  try {
    correct(*path);
  } catch (const std::exception& e) {
    ROS_WARN_THROTTLE(1.0, "fragg_map: corrected_path refused: %s", e.what());
  }
}

void PathCorrector::correct(const nav_msgs::Path& path) {
  const std::string& map_frame = params_.frame_id;
  const std::string& child_frame = params_.correction.path_child_frame;
  const int64_t tolerance_ns = std::llround(params_.correction.stamp_tolerance_s * 1e9);
  // Every pose is checked before anything is looked up.
  std::vector<PoseRequest> requests(path.poses.size());
  for (size_t i = 0; i < path.poses.size(); ++i) {
    const geometry_msgs::PoseStamped& p = path.poses[i];
    const std::string frame =
        withoutLeadingSlash(p.header.frame_id.empty() ? path.header.frame_id : p.header.frame_id);
    if (!frame.empty() && frame != map_frame)
      throw fragg::InvalidArgument("pose " + std::to_string(i) + " is in '" + frame +
                                   "', not in frame_id '" + map_frame + "'");
    requests[i].stamp_ns = static_cast<int64_t>(p.header.stamp.toNSec());
    try {
      requests[i].T_map_sensor = isometryFromPose(p.pose);
    } catch (const fragg::InvalidArgument& e) {
      throw fragg::InvalidArgument("pose " + std::to_string(i) + ": " + e.what());
    }
  }

  // The transforms child_frame -> the scan's cloud frame are looked up with no lock held: tf
  // may be slow, and the write lock would hold insertion and every query back meanwhile. The
  // scans are found under the read lock, placed without a lock, and planned and moved under
  // the write lock (a scan gone in between is reported as naming no kept scan).
  size_t unplaced = 0;
  if (!child_frame.empty()) {
    struct ToPlace {
      size_t request;
      std::string sensor_frame;
      int64_t stamp_ns;
    };
    std::vector<ToPlace> to_place;
    std::vector<bool> unknown(requests.size(), false);
    {
      const SharedMap::ReadGuard state = shared_->read("corrected_path");
      requireKeptScans(state->map);
      for (size_t i = 0; i < requests.size(); ++i) {
        const ScanStampIndex::Entry* entry = state->stamps.find(requests[i].stamp_ns, tolerance_ns);
        if (!entry) {
          unknown[i] = true;  // planCorrection reports it
          continue;
        }
        if (entry->sensor_frame.empty()) {  // kept by an older map file or a non-ROS build
          ++unplaced;
          continue;
        }
        to_place.push_back(
            {i, entry->sensor_frame, state->map.scanStore().record(entry->id).stamp_ns});
      }
    }
    // Path poses of child_frame -> sensor poses (tf child_frame -> the scan's cloud frame at
    // the scan's stamp; a static transform is found at any time). Poses that cannot be placed
    // are left out (and counted); those naming no scan are reported by the plan.
    std::vector<PoseRequest> placed;
    placed.reserve(requests.size());
    for (size_t i = 0; i < requests.size(); ++i)
      if (unknown[i]) placed.push_back(requests[i]);
    for (const ToPlace& p : to_place) {
      try {
        ::ros::Time stamp;
        stamp.fromNSec(static_cast<uint64_t>(p.stamp_ns));
        const Eigen::Isometry3d T_child_sensor =
            tf2::transformToEigen(tf_.lookupTransform(child_frame, p.sensor_frame, stamp));
        const PoseRequest& r = requests[p.request];
        placed.push_back({r.stamp_ns, sensorPoseFromChild(r.T_map_sensor, T_child_sensor)});
      } catch (const tf2::TransformException& e) {
        ++unplaced;
        ROS_WARN_THROTTLE(5.0, "fragg_map: corrected_path: no transform %s <- %s: %s",
                          child_frame.c_str(), p.sensor_frame.c_str(), e.what());
      }
    }
    requests.swap(placed);
  }

  CorrectionPlan plan;
  double ms = 0.0;
  {
    const SharedMap::WriteGuard state = shared_->write("corrected_path");
    requireKeptScans(state->map);
    const PoseThresholds& thresholds = params_.correction.thresholds;
    plan =
        planCorrection(requests, state->stamps, state->map.scanStore(), tolerance_ns, &thresholds);
    ms = applyCorrection(plan, &state->map, stats_);
  }
  if (plan.T_map_sensor_new.empty()) {
    ROS_DEBUG("fragg_map: corrected_path: no kept scan moved (%zu poses, %zu within thresholds)",
              path.poses.size(), plan.unchanged);
    return;
  }
  ROS_INFO(
      "fragg_map: corrected_path moved %zu scans in %.1f ms (%zu poses: %zu within thresholds, "
      "%zu naming no kept scan, %zu without a transform %s -> sensor)",
      plan.T_map_sensor_new.size(), ms, path.poses.size(), plan.unchanged, plan.unknown.size(),
      unplaced, child_frame.empty() ? "-" : child_frame.c_str());
  if (on_corrected_) on_corrected_();
}

}  // namespace fragg::ros
