// Dataset folders the core reads back (fragg::openDataset), written frame by frame:
//  * KITTI-style LiDAR sequence: velodyne/NNNNNN.bin (valid returns only), poses.txt
//    (ground-truth sensor poses, 3x4 row-major), calib.txt (Tr = identity, so the poses are
//    the LiDAR's), times.txt; beside them poses_odom.txt (the drifting odometry's sensor poses,
//    same format), and with `organised` an organised/ folder of binary PCDs (NaN = no return)
//    with its TUM poses.txt, which the core reads as a folder of PCD scans.
//  * depth-image folder: depth/NNNNNN.pgm (16-bit millimetres, 0 = no return), pose.txt (TUM,
//    ground truth, camera optical frame), intrinsics.txt, pose_odom.txt.
// With per-point dynamic labels (scenes with movers), both also write labels/NNNNNN.dyn: one
// byte a point as the dataset reader gives the scan back, finite points only and in order
// (a KITTI .bin's records; a depth image's non-zero pixels, row by row): 1 = the return is
// from a moving object, 0 = static (readDynamicLabels reads them).
// Files are written atomically; throws IoError.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "fragg_map/io/depth_image.h"
#include "fragg_map/point_cloud.h"

namespace fragg::sim {

class KittiFolderWriter {
 public:
  KittiFolderWriter(const std::string& dir, bool organised);
  /// Writes one scan; `dynamic_labels` (null: none) has one flag a point of `cloud_S`.
  void add(const PointCloud& cloud_S, const Eigen::Isometry3d& T_map_sensor,
           const Eigen::Isometry3d& T_odom_sensor, double stamp_s,
           const std::vector<uint8_t>* dynamic_labels = nullptr);
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
  /// Writes one frame; `dynamic_labels` (null: none) has one flag a pixel of `cloud_C`.
  void add(const PointCloud& cloud_C, const Eigen::Isometry3d& T_map_camera,
           const Eigen::Isometry3d& T_odom_camera, double stamp_s,
           const std::vector<uint8_t>* dynamic_labels = nullptr);
  void finish();

 private:
  std::string dir_;
  DepthIntrinsics intrinsics_;
  std::vector<Eigen::Isometry3d> gt_, odom_;
  std::vector<double> stamps_;
};

/// The labels of scan `index` of a dataset folder written with labels (labels/NNNNNN.dyn):
/// one flag a finite point. Throws IoError when the file is missing or holds a value > 1.
std::vector<uint8_t> readDynamicLabels(const std::string& dir, size_t index);

/// Binary 16-bit PGM (P5, big-endian samples), atomically.
void writePgm16(const std::string& path, const DepthImage& image);
/// "stamp tx ty tz qx qy qz qw" per pose.
std::string tumPoseLines(const std::vector<Eigen::Isometry3d>& poses,
                         const std::vector<double>& stamps_s);
/// 12 numbers per pose: the first three rows of the matrix, row-major.
std::string kittiPoseLines(const std::vector<Eigen::Isometry3d>& poses);

}  // namespace fragg::sim
