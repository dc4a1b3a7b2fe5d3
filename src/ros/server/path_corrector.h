// corrected_path (nav_msgs/Path, as pose-graph back ends publish their keyframes): every pose
// whose stamp names a kept scan gives that scan's new sensor pose (directly, or through tf
// correction/path_child_frame -> the cloud's frame at the scan's stamp); the scans that moved
// beyond correction/min_translation or min_rotation are corrected in one batch, one log line
// per correction. A path in another frame than frame_id, or with a bad pose, is refused whole.
#pragma once

#include <nav_msgs/Path.h>
#include <ros/node_handle.h>
#include <ros/subscriber.h>
#include <tf2_ros/buffer.h>

#include <functional>

#include "fragg_map/ros/server_params.h"
#include "server_stats.h"
#include "shared_map.h"

namespace fragg::ros {

class PathCorrector {
 public:
  /// `on_corrected` runs (map unlocked) after a correction that moved at least one scan.
  PathCorrector(::ros::NodeHandle& nh, const ServerParams& params, const tf2_ros::Buffer& tf,
                SharedMap* shared, ServerStats* stats, std::function<void()> on_corrected);

 private:
  void onPath(const nav_msgs::Path::ConstPtr& path);
  /// Corrects the scans the path moves; throws fragg::InvalidArgument when it refuses the path.
  void correct(const nav_msgs::Path& path);

  const ServerParams params_;
  const tf2_ros::Buffer& tf_;
  SharedMap* shared_;
  ServerStats* stats_;
  std::function<void()> on_corrected_;
  ::ros::Subscriber sub_;
};

}  // namespace fragg::ros
