// Dataset readers: a sequence of scans (cloud in the sensor frame + sensor pose in the map
// frame). `openDataset` picks the reader from what INPUT is.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "fragg_map/point_cloud.h"

namespace fragg {

struct Scan {
  PointCloud cloud;  ///< sensor frame
  Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
  int64_t stamp_ns = 0;  ///< 0 when the dataset has no time stamps
  std::string source;    ///< file or topic it came from (for messages)
};

class ScanSource {
 public:
  virtual ~ScanSource() = default;
  /// Reads the next scan; false at the end. Throws IoError on malformed input.
  virtual bool next(Scan& scan) = 0;
  /// Number of scans when known up front (for progress bars), else nullopt.
  virtual std::optional<size_t> size() const = 0;
  virtual std::string describe() const = 0;
  /// Scans left out so far because they could not be placed (a bag cloud with no transform
  /// to the fixed frame at its stamp), and the reason for the last one. A source that can
  /// place none of its scans throws IoError instead.
  virtual size_t skipped() const { return 0; }
  virtual std::string lastSkipReason() const { return {}; }
};

struct DatasetOptions {
  std::string topic;          ///< bag: PointCloud2 topic ("" = the only one)
  std::string frame = "map";  ///< bag: fixed frame the sensor pose is looked up in
};

/// Opens INPUT, which may be: a ROS bag (.bag, built with ROS only), an OctoMap ScanGraph
/// (.graph), a KITTI odometry sequence folder (velodyne/ + poses.txt + calib.txt), a folder of
/// PCD (or PLY) files with a TUM poses.txt, a depth-image folder (depth/*.pgm + pose.txt,
/// 640x480 Kinect intrinsics unless an intrinsics.txt says otherwise), or one point cloud file
/// (.pcd, .ply, .xyz/.dat/.txt ASCII "x y z", .bin KITTI float32 x4) with the sensor at the
/// origin (a PCD's VIEWPOINT becomes the pose). Throws IoError naming the path and the problem.
std::unique_ptr<ScanSource> openDataset(const std::string& input,
                                        const DatasetOptions& options = {});

/// Opens one kind of input. The ROS-free core cannot read bags; the fragg_map_rosbag library
/// registers its reader with registerBagOpener (see fragg_map/io/rosbag_source.h).
using DatasetOpener =
    std::function<std::unique_ptr<ScanSource>(const std::string&, const DatasetOptions&)>;

/// Installs the opener openDataset uses for .bag inputs (replacing an earlier one; an empty
/// function removes it). Thread-safe.
void registerBagOpener(DatasetOpener opener);

}  // namespace fragg
