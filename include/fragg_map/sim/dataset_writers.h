// Dataset folders the core reads back (fragg::openDataset), written frame by frame:
//  * KITTI-style LiDAR sequence: velodyne/NNNNNN.bin (valid returns only), poses.txt
//    (ground-truth sensor poses, 3x4 row-major), calib.txt (Tr = identity, so the poses are
//    the LiDAR's), times.txt; beside them poses_odom.txt (the drifting odometry's sensor poses,
//    same format), and with `organised` an organised/ folder of binary PCDs (NaN = no return)
//    with its TUM poses.txt, which the core reads as a folder of PCD scans.
//  * depth-image folder: depth/NNNNNN.pgm (16-bit millimetres, 0 = no return), pose.txt (TUM,
//    ground truth, camera optical frame), intrinsics.txt, pose_odom.txt.
// Files are written atomically; throws IoError.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "fragg_map/io/depth_image.h"
#include "fragg_map/point_cloud.h"

namespace fragg::sim {

class KittiFolderWriter {
 public:
  KittiFolderWriter(const std::string& dir, bool organised);
  void add(const PointCloud& cloud_S, const Eigen::Isometry3d& T_map_sensor,
           const Eigen::Isometry3d& T_odom_sensor, double stamp_s);
  void finish();  ///< writes the pose, time and calibration files

 private:
  std::string dir_;
  bool organised_;
  std::vector<Eigen::Isometry3d> gt_, odom_;
  std::vector<double> stamps_;
};

class DepthFolderWriter {
 public:
  DepthFolderWriter(const std::string& dir, const DepthIntrinsics& intrinsics);
  void add(const PointCloud& cloud_C, const Eigen::Isometry3d& T_map_camera,
           const Eigen::Isometry3d& T_odom_camera, double stamp_s);
  void finish();

 private:
  std::string dir_;
  DepthIntrinsics intrinsics_;
  std::vector<Eigen::Isometry3d> gt_, odom_;
  std::vector<double> stamps_;
};

/// Binary 16-bit PGM (P5, big-endian samples), atomically.
void writePgm16(const std::string& path, const DepthImage& image);
/// "stamp tx ty tz qx qy qz qw" per pose.
std::string tumPoseLines(const std::vector<Eigen::Isometry3d>& poses,
                         const std::vector<double>& stamps_s);
/// 12 numbers per pose: the first three rows of the matrix, row-major.
std::string kittiPoseLines(const std::vector<Eigen::Isometry3d>& poses);

}  // namespace fragg::sim
