// ~correct_poses: check every argument, match stamps to kept scans, correct in one batch.
#include "correction_service.h"

#include <ros/console.h>

#include <cmath>
#include <string>
#include <vector>

#include "apply_correction.h"
#include "fragg_map/errors.h"
#include "fragg_map/ros/pose_correction.h"

namespace fragg::ros {
namespace {

// The requests, every pose checked; throws fragg::InvalidArgument naming the bad one.
std::vector<PoseRequest> requestsFrom(const fragg_map::CorrectPoses::Request& req) {
  if (req.stamps.empty()) throw fragg::InvalidArgument("no stamps given");
  if (req.stamps.size() != req.poses.size())
    throw fragg::InvalidArgument(std::to_string(req.stamps.size()) + " stamps but " +
                                 std::to_string(req.poses.size()) + " poses");
  std::vector<PoseRequest> requests(req.stamps.size());
  for (size_t i = 0; i < requests.size(); ++i) {
    requests[i].stamp_ns = static_cast<int64_t>(req.stamps[i].toNSec());
    try {
      requests[i].T_map_sensor = isometryFromPose(req.poses[i]);
    } catch (const fragg::InvalidArgument& e) {
      throw fragg::InvalidArgument("pose " + std::to_string(i) + ": " + e.what());
    }
  }
  return requests;
}

}  // namespace

CorrectionService::CorrectionService(::ros::NodeHandle& private_nh, const ServerParams& params,
                                     SharedMap* shared, ServerStats* stats,
                                     std::function<void()> on_corrected)
    : params_(params), shared_(shared), stats_(stats), on_corrected_(std::move(on_corrected)) {
  service_ = private_nh.advertiseService("correct_poses", &CorrectionService::correct, this);
}

bool CorrectionService::correct(fragg_map::CorrectPoses::Request& req,
                                fragg_map::CorrectPoses::Response& res) {
  res.corrected = 0;
  res.ms = 0.0;
  res.unknown_stamps.clear();
  try {
    const std::vector<PoseRequest> requests = requestsFrom(req);
    const int64_t tolerance_ns = std::llround(params_.correction.stamp_tolerance_s * 1e9);
    std::string unknown_reason;
    {
      const SharedMap::WriteGuard state = shared_->write("pose correction service");
      requireKeptScans(state->map);
      const CorrectionPlan plan =
          planCorrection(requests, state->stamps, state->map.scanStore(), tolerance_ns,
                         nullptr);  // asked for explicitly: every matched scan moves
      res.ms = applyCorrection(plan, &state->map, stats_);
      res.corrected = static_cast<uint32_t>(plan.T_map_sensor_new.size());
      for (size_t i : plan.unknown) res.unknown_stamps.push_back(req.stamps[i]);
      unknown_reason = describeUnknown(plan);
    }
    res.success = true;
    res.message = "corrected " + std::to_string(res.corrected) + " scans in " +
                  std::to_string(res.ms) + " ms; " + unknown_reason;
    if (res.corrected > 0) {
      ROS_INFO("fragg_map: ~correct_poses moved %u scans in %.1f ms (%zu unknown stamps)",
               res.corrected, res.ms, res.unknown_stamps.size());
      if (on_corrected_) on_corrected_();
    }
  } catch (const std::exception& e) {
    res.success = false;
    res.message = e.what();
    res.corrected = 0;
    res.unknown_stamps.clear();
    ROS_WARN_THROTTLE(1.0, "fragg_map: correct_poses refused: %s", e.what());
  }
  return true;
}

}  // namespace fragg::ros
