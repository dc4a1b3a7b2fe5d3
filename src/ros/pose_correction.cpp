// Pose checks and the correction plan of the map server.
#include "fragg_map/ros/pose_correction.h"

#include <cmath>
#include <string>

#include "fragg_map/errors.h"

namespace fragg::ros {

Eigen::Isometry3d isometryFromPose(const geometry_msgs::Pose& pose) {
  const Eigen::Vector3d t(pose.position.x, pose.position.y, pose.position.z);
  Eigen::Quaterniond q(pose.orientation.w, pose.orientation.x, pose.orientation.y,
                       pose.orientation.z);
  if (!t.allFinite() || !q.coeffs().allFinite()) throw fragg::InvalidArgument("pose is not finite");
  const double norm = q.norm();
  if (std::abs(norm - 1.0) > 1e-3)
    throw fragg::InvalidArgument("orientation is not a unit quaternion (norm " +
                                 std::to_string(norm) + ")");
  q.normalize();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = t;
  return T;
}

bool poseMoved(const Eigen::Isometry3d& T_old, const Eigen::Isometry3d& T_new,
               const PoseThresholds& thresholds) {
  const double moved_m = (T_new.translation() - T_old.translation()).norm();
  const double turned_rad = Eigen::AngleAxisd(T_old.linear().transpose() * T_new.linear()).angle();
  return moved_m > thresholds.min_translation_m || turned_rad > thresholds.min_rotation_rad;
}

CorrectionPlan planCorrection(const std::vector<PoseRequest>& requests, const ScanStampIndex& index,
                              const fragg::ScanStore& store, int64_t tolerance_ns,
                              const PoseThresholds* thresholds) {
  CorrectionPlan plan;
  std::map<fragg::ScanId, size_t> matched;  // scan -> request index
  for (size_t i = 0; i < requests.size(); ++i) {
    const PoseRequest& r = requests[i];
    const ScanStampIndex::Entry* entry = index.find(r.stamp_ns, tolerance_ns);
    if (!entry || !store.contains(entry->id) || !store.canRemove(entry->id)) {
      plan.unknown.push_back(i);
      continue;
    }
    const auto [it, fresh] = matched.emplace(entry->id, i);
    if (!fresh)
      throw fragg::InvalidArgument("poses " + std::to_string(it->second) + " and " +
                                   std::to_string(i) + " both name scan " +
                                   std::to_string(entry->id));
    if (thresholds &&
        !poseMoved(store.record(entry->id).T_map_sensor, r.T_map_sensor, *thresholds)) {
      ++plan.unchanged;
      continue;
    }
    plan.T_map_sensor_new.emplace(entry->id, r.T_map_sensor);
  }
  return plan;
}

}  // namespace fragg::ros
