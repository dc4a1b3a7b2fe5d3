// The ROS-free rules of loop-closure correction in the map server: a geometry_msgs/Pose as a
// checked rigid transform, when a pose has moved enough to be corrected, the sensor pose from a
// path pose of another frame, and the plan (stamp -> kept scan -> new pose) that
// ~correct_poses and corrected_path hand to fragg::Map::correctPoses.
#pragma once

#include <geometry_msgs/Pose.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "fragg_map/ros/scan_stamp_index.h"
#include "fragg_map/scan_store.h"

namespace fragg::ros {

/// Poses closer than both thresholds to the kept pose are left alone (corrected_path).
struct PoseThresholds {
  double min_translation_m = 0.05;
  double min_rotation_rad = 0.01;
};

/// The pose as T_map_sensor (quaternion normalised). Throws fragg::InvalidArgument for a
/// non-finite value or a quaternion whose norm is not 1 within 1e-3.
Eigen::Isometry3d isometryFromPose(const geometry_msgs::Pose& pose);

/// Whether `T_new` differs from `T_old` by more than min_translation_m (distance of the
/// origins) or more than min_rotation_rad (angle of T_old^-1 T_new).
bool poseMoved(const Eigen::Isometry3d& T_old, const Eigen::Isometry3d& T_new,
               const PoseThresholds& thresholds);

/// The sensor pose from the pose of the frame a path gives (T_map_child) and the transform
/// child -> sensor frame (T_child_sensor, from tf at the scan's stamp).
inline Eigen::Isometry3d sensorPoseFromChild(const Eigen::Isometry3d& T_map_child,
                                             const Eigen::Isometry3d& T_child_sensor) {
  return T_map_child * T_child_sensor;
}

/// One requested correction: a scan named by its stamp and its new sensor pose.
struct PoseRequest {
  int64_t stamp_ns = 0;
  Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
};

struct CorrectionPlan {
  std::map<fragg::ScanId, Eigen::Isometry3d> T_map_sensor_new;  ///< for Map::correctPoses
  /// Requests (indices) that match no kept scan within the tolerance, a scan whose points
  /// were dropped by the store's budget, or one that can no longer be removed exactly
  /// (ScanStore::canRemove: clear_bbox changed cells it had updated).
  std::vector<size_t> unknown;
  /// Why, per cause (they add up to unknown.size()): no scan within the tolerance; a scan
  /// that is no longer kept (the store's budget dropped its points); a kept scan that an edit
  /// reached (clear_bbox / clear_bbx, truncate, merge), which cannot be removed exactly.
  size_t unknown_no_scan = 0, unknown_not_kept = 0, unknown_edited = 0;
  size_t unchanged = 0;  ///< matched, but within the thresholds (only with thresholds)
};

/// One sentence on the plan's unknown requests and why, e.g. "2 stamps name no scan that can be
/// corrected: 1 matches no scan within correction/stamp_tolerance, 1 names a scan an edit
/// reached (clear_bbox, truncate, merge: its updates can no longer be undone exactly)"; "0
/// stamps name no scan that can be corrected" when there are none.
std::string describeUnknown(const CorrectionPlan& plan);

/// Matches each request to a kept scan (the nearest stamp within tolerance_ns) and, with
/// `thresholds`, keeps only the scans whose pose moved beyond them. Throws
/// fragg::InvalidArgument when two requests match the same scan.
CorrectionPlan planCorrection(const std::vector<PoseRequest>& requests, const ScanStampIndex& index,
                              const fragg::ScanStore& store, int64_t tolerance_ns,
                              const PoseThresholds* thresholds);

}  // namespace fragg::ros
