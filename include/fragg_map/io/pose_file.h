// Pose lists of the supported dataset layouts. Poses are T_world_frame: p_world = T * p_frame.
// Every reader throws fragg::IoError naming the file, the line and the problem.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace fragg {

struct StampedPose {
  double stamp_s = 0.0;  ///< seconds; 0 when the file has no time stamps
  Eigen::Isometry3d T_world_frame = Eigen::Isometry3d::Identity();
};

/// TUM trajectory: "timestamp tx ty tz qx qy qz qw" per line, or "tx ty tz qx qy qz qw"
/// (slambook's pose.txt, stamps 0). Quaternions are normalised; non-unit ones are rejected.
std::vector<StampedPose> readTumPoses(const std::string& path);

/// Corrected scan poses for `fragg_map correct`: "scan_index tx ty tz qx qy qz qw" per line
/// (T_map_sensor; the index is the scan's insertion order). Indices must not repeat.
std::map<uint64_t, Eigen::Isometry3d> readScanPoses(const std::string& path);

/// KITTI odometry poses: 12 numbers per line, the first three rows of T_cam0_camI, row-major.
std::vector<Eigen::Isometry3d> readKittiPoses(const std::string& path);

/// KITTI odometry calib.txt: the "Tr:" (or "Tr_velo_to_cam:") line, 12 numbers row-major:
/// T_cam_velo, the velodyne pose in the camera frame.
Eigen::Isometry3d readKittiCalibTr(const std::string& path);

/// A 4x4 rigid transform as text, row-major (16 numbers over any lines; last row 0 0 0 1),
/// e.g. small_gicp's T_target_source.txt.
Eigen::Isometry3d readMatrix4(const std::string& path);

/// KITTI times.txt: one time in seconds per line.
std::vector<double> readKittiTimes(const std::string& path);

}  // namespace fragg
