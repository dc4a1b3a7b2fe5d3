// ~correct_poses: moves kept scans to corrected sensor poses named by stamp (loop closure).
// Stamps naming no kept scan come back in unknown_stamps while the others are corrected; bad
// arguments answer success=false and leave the map untouched. The map stays locked for the
// whole correction (the insertion thread waits).
#pragma once

#include <ros/node_handle.h>
#include <ros/service_server.h>

#include <functional>

#include "fragg_map/CorrectPoses.h"
#include "fragg_map/ros/server_params.h"
#include "server_stats.h"
#include "shared_map.h"

namespace fragg::ros {

class CorrectionService {
 public:
  /// `on_corrected` runs (map unlocked) after a correction that moved at least one scan.
  CorrectionService(::ros::NodeHandle& private_nh, const ServerParams& params, SharedMap* shared,
                    ServerStats* stats, std::function<void()> on_corrected);

 private:
  bool correct(fragg_map::CorrectPoses::Request& req, fragg_map::CorrectPoses::Response& res);

  const ServerParams params_;
  SharedMap* shared_;
  ServerStats* stats_;
  std::function<void()> on_corrected_;
  ::ros::ServiceServer service_;
};

}  // namespace fragg::ros
