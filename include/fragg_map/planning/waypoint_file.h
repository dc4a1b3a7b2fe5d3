// Waypoint files for collision checks: one pose a line, "x y z qx qy qz qw" (T_map_shape:
// position in metres, unit quaternion), blank lines and lines starting with '#' ignored.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace fragg::planning {

/// Quaternions whose norm is off 1 by more than this are refused.
constexpr double kQuaternionNormTolerance = 1e-6;

/// Throws IoError naming the file and line for an unreadable file, a malformed line (not seven
/// finite numbers) or a quaternion that is not unit; an empty file gives no poses.
std::vector<Eigen::Isometry3d> readWaypoints(const std::string& path);

/// One line's pose (the same rules); throws InvalidArgument with the reason.
Eigen::Isometry3d parseWaypoint(const std::string& line);

}  // namespace fragg::planning
