// ROS bag output of the simulator (built only with ROS, in fragg_map_sim_bag; the header is
// ROS-free). Per frame: the organised cloud as sensor_msgs/PointCloud2 in the sensor frame
// (x y z float32, plus ring uint16 for a LiDAR; NaN = no return), /tf with map -> odom
// (identity: no localisation correction) and odom -> base_link (the drifting odometry), and
// the ground-truth base pose (geometry_msgs/PoseStamped in map). Once: /tf_static
// base_link -> sensor at the start and, at the end, a nav_msgs/Path of the ground-truth base
// poses of every frame (the keyframes). Stamps are start_s + the trajectory time.
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <string>

#include "fragg_map/point_cloud.h"
#include "fragg_map/sim/trajectory.h"

namespace fragg::sim {

struct BagNames {
  std::string map_frame = "map";
  std::string odom_frame = "odom";
  std::string base_frame = "base_link";
  std::string sensor_frame = "lidar";
  std::string cloud_topic = "/points";
  std::string gt_pose_topic = "/ground_truth/pose";
  std::string gt_path_topic = "/ground_truth/path";
  double start_s = 1700000000.0;  ///< fixed, so the same run gives the same bytes
};

class SimBagWriter {
 public:
  /// Opens the bag for writing (throws IoError) and writes /tf_static.
  SimBagWriter(const std::string& path, const BagNames& names,
               const Eigen::Isometry3d& T_base_sensor, bool lidar_rings);
  ~SimBagWriter();
  void add(const PointCloud& cloud_S, const PoseSample& pose);
  /// Writes the path and closes the bag.
  void finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace fragg::sim
