// Eigen points as geometry_msgs, for the marker builders of src/ros.
#pragma once

#include <geometry_msgs/Point.h>

#include <Eigen/Core>

namespace fragg::ros {

/// The point `p` as a geometry_msgs::Point (same frame, metres).
[[nodiscard]] inline geometry_msgs::Point toPoint(const Eigen::Vector3d& p) {
  geometry_msgs::Point m;
  m.x = p.x();
  m.y = p.y();
  m.z = p.z();
  return m;
}

}  // namespace fragg::ros
