// Single point-cloud files (sensor frame), and writing occupied-voxel centres.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "fragg_map/point_cloud.h"

namespace fragg {

/// PCD v0.7 (ascii, binary, binary_compressed; x y z as F4 or F8; organised kept).
PointCloud readPcd(const std::string& path);
/// PLY (ascii, binary little/big endian; float or double x y z). All-zero points (a common
/// "no return" marker) are kept as NaN.
PointCloud readPly(const std::string& path);
/// ASCII "x y z [...]" per line ('#' comments ignored); .bz2 is not read (decompress first).
PointCloud readXyz(const std::string& path);
/// KITTI velodyne .bin: float32 x y z intensity.
PointCloud readKittiBin(const std::string& path);
/// By extension: .pcd .ply .xyz .dat .txt .bin.
PointCloud readPointFile(const std::string& path);

/// Writers (atomic: temporary file + rename). Binary little-endian.
void writePly(const std::string& path, const std::vector<Eigen::Vector3f>& points);
void writePcd(const std::string& path, const std::vector<Eigen::Vector3f>& points);

}  // namespace fragg
