// LINE_LIST outline of a sensor's frustum in the map frame.
#include "fragg_map/ros/frustum_marker.h"

#include <cmath>
#include <vector>

#include "fragg_map/errors.h"
#include "point_msg.h"

namespace fragg::ros {
namespace {

// Corners of the pinhole pyramid's far plane in the sensor frame.
std::vector<Eigen::Vector3d> pinholeCorners_S(const fragg::SensorModel& s) {
  const Eigen::Vector3d up_S = s.forward_S.cross(s.right_S).normalized();
  const double tx = std::tan(s.hfov_rad / 2), ty = std::tan(s.vfov_rad / 2);
  std::vector<Eigen::Vector3d> corners;
  for (const auto& [sx, sy] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
    const Eigen::Vector3d dir = s.forward_S + sx * tx * s.right_S + sy * ty * up_S;
    corners.push_back(dir.normalized() * s.max_range_m);
  }
  return corners;
}

}  // namespace

visualization_msgs::Marker frustumMarker(const fragg::SensorModel& sensor,
                                         const Eigen::Isometry3d& T_map_sensor,
                                         const std::string& frame_id, const ::ros::Time& stamp,
                                         int segments) {
  if (sensor.type == fragg::SensorType::kAuto)
    throw fragg::InvalidArgument("frustum marker needs an explicit sensor model");
  if (!(sensor.max_range_m > 0.0))
    throw fragg::InvalidArgument("frustum marker needs a positive max range");
  if (segments < 3) throw fragg::InvalidArgument("frustum marker needs >= 3 segments");
  visualization_msgs::Marker m;
  m.header.frame_id = frame_id;
  m.header.stamp = stamp;
  m.ns = "frustum";
  m.id = 0;
  m.type = visualization_msgs::Marker::LINE_LIST;
  m.action = visualization_msgs::Marker::ADD;
  m.pose.orientation.w = 1.0;
  m.scale.x = 0.02;  // line width [m]
  m.color.r = 1.0f;
  m.color.g = 0.8f;
  m.color.b = 0.0f;
  m.color.a = 1.0f;
  auto line = [&](const Eigen::Vector3d& a_S, const Eigen::Vector3d& b_S) {
    m.points.push_back(toPoint(T_map_sensor * a_S));
    m.points.push_back(toPoint(T_map_sensor * b_S));
  };
  if (sensor.type == fragg::SensorType::kPinhole) {
    const std::vector<Eigen::Vector3d> c = pinholeCorners_S(sensor);
    for (int i = 0; i < 4; ++i) {
      line(Eigen::Vector3d::Zero(), c[i]);
      line(c[i], c[(i + 1) % 4]);
    }
    return m;
  }
  // Spinning LiDAR: rims of the upper and lower cones at max range, plus a few generators.
  const double r = sensor.max_range_m;
  auto rim_S = [&](double elevation, double azimuth) {
    return Eigen::Vector3d(r * std::cos(elevation) * std::cos(azimuth),
                           r * std::cos(elevation) * std::sin(azimuth), r * std::sin(elevation));
  };
  for (int i = 0; i < segments; ++i) {
    const double a0 = 2 * M_PI * i / segments, a1 = 2 * M_PI * (i + 1) / segments;
    for (double e : {sensor.elevation_min_rad, sensor.elevation_max_rad})
      line(rim_S(e, a0), rim_S(e, a1));
    if (i % (segments / 4 > 0 ? segments / 4 : 1) == 0) {
      line(Eigen::Vector3d::Zero(), rim_S(sensor.elevation_min_rad, a0));
      line(Eigen::Vector3d::Zero(), rim_S(sensor.elevation_max_rad, a0));
    }
  }
  return m;
}

}  // namespace fragg::ros
