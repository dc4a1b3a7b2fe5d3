// Single point-cloud files (sensor frame), and writing point sets. Every reader throws
// fragg::IoError naming the path and the problem (missing file, wrong magic, bad header,
// truncated data); none of them exits or crashes on a malformed file.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "fragg_map/point_cloud.h"

namespace fragg {

/// PCD v0.7 (and the older v0.5/v0.6 headers): DATA ascii, binary or binary_compressed (LZF);
/// x y z as F4 or F8, other fields skipped; organised clouds keep width x height and NaNs.
/// The points are returned in the sensor frame: a non-identity VIEWPOINT (the sensor pose in
/// the file's frame, "tx ty tz qw qx qy qz") is applied inversely, and stored in
/// `T_file_sensor` when it is given, so that T_file_sensor * points_S gives the file's points.
PointCloud readPcd(const std::string& path, Eigen::Isometry3d* T_file_sensor = nullptr);
/// PLY (ascii, binary_little_endian, binary_big_endian; x y z of any scalar type, float or
/// double in practice; other properties and elements skipped). Points exactly at (0,0,0) (a
/// common "no return" marker) become NaN.
PointCloud readPly(const std::string& path);
/// ASCII "x y z [...]" per line (spaces, tabs or commas; '#' comment lines and blank lines
/// ignored); .bz2 is not read (decompress first).
PointCloud readXyz(const std::string& path);
/// KITTI velodyne .bin: float32 x y z intensity per point.
PointCloud readKittiBin(const std::string& path);
/// By extension: .pcd .ply .xyz .dat .txt .bin (case-insensitive).
PointCloud readPointFile(const std::string& path);

/// Writers (atomic: temporary file + rename; a failed write leaves no partial file). Binary
/// little-endian float32 x y z.
void writePly(const std::string& path, const std::vector<Eigen::Vector3f>& points);
void writePcd(const std::string& path, const std::vector<Eigen::Vector3f>& points);
/// PCD keeping an organised cloud's width x height and its NaN points (DATA binary).
void writePcd(const std::string& path, const PointCloud& cloud);
/// KITTI .bin (float32 x y z intensity, intensity 0); NaN/Inf points are left out.
void writeKittiBin(const std::string& path, const PointCloud& cloud);

}  // namespace fragg
