// Pose checks and the correction plan of the map server.
#include "fragg_map/ros/pose_correction.h"

#include <cmath>
#include <string>
#include <vector>

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

std::string describeUnknown(const CorrectionPlan& plan) {
  const size_t n = plan.unknown.size();
  std::string s = std::to_string(n) + (n == 1 ? " stamp names" : " stamps name") +
                  " no scan that can be corrected";
  if (n == 0) return s;
  std::vector<std::string> parts;
  auto count = [](size_t k, const char* one, const char* many) {
    return std::to_string(k) + (k == 1 ? one : many);
  };
  if (plan.unknown_no_scan > 0)
    parts.push_back(count(plan.unknown_no_scan, " matches no scan", " match no scan") +
                    " within correction/stamp_tolerance");
  if (plan.unknown_not_kept > 0)
    parts.push_back(count(plan.unknown_not_kept, " names a scan", " name scans") +
                    " no longer kept (the scan store's budget dropped the points)");
  if (plan.unknown_edited > 0)
    parts.push_back(count(plan.unknown_edited, " names a scan", " name scans") +
                    " an edit reached (clear_bbox / clear_bbx, truncate, merge: the updates can "
                    "no longer be undone exactly)");
  s += ": ";
  for (size_t i = 0; i < parts.size(); ++i) s += (i > 0 ? "; " : "") + parts[i];
  return s;
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
      if (!entry)
        ++plan.unknown_no_scan;
      else if (!store.contains(entry->id) || !store.hasPoints(entry->id))
        ++plan.unknown_not_kept;
      else
        ++plan.unknown_edited;  // kept, with its points, but an edit reached its cells
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
