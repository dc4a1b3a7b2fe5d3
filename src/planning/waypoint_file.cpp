#include "fragg_map/planning/waypoint_file.h"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "fragg_map/errors.h"

namespace fragg::planning {

Eigen::Isometry3d parseWaypoint(const std::string& line) {
  std::istringstream in(line);
  double v[7];
  for (int i = 0; i < 7; ++i) {
    std::string token;
    if (!(in >> token))
      throw InvalidArgument(fmt::format("expected 7 numbers (x y z qx qy qz qw), got {}", i));
    size_t used = 0;
    try {
      v[i] = std::stod(token, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != token.size() || !std::isfinite(v[i]))
      throw InvalidArgument(fmt::format("'{}' is not a finite number", token));
  }
  std::string extra;
  if (in >> extra)
    throw InvalidArgument(
        fmt::format("expected 7 numbers (x y z qx qy qz qw), found more: '{}'", extra));
  const Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
  const double norm = q.norm();
  if (std::abs(norm - 1.0) > kQuaternionNormTolerance)
    throw InvalidArgument(fmt::format("quaternion norm is {:.9f}, not 1 (within {})", norm,
                                      kQuaternionNormTolerance));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  return T;
}

std::vector<Eigen::Isometry3d> readWaypoints(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError("cannot read waypoint file " + path);
  std::vector<Eigen::Isometry3d> poses;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    try {
      poses.push_back(parseWaypoint(line));
    } catch (const InvalidArgument& e) {
      throw IoError(fmt::format("{}:{}: {}", path, line_no, e.what()));
    }
  }
  if (in.bad()) throw IoError("error reading waypoint file " + path);
  return poses;
}

}  // namespace fragg::planning
