// A sensor model placed in the map -> visualization_msgs/Marker LINE_LIST of its frustum
// (pinhole: the pyramid from the sensor to the far plane; spinning LiDAR: the two elevation
// cones and the far rim, drawn with `segments` azimuth steps).
#pragma once

#include <ros/time.h>
#include <visualization_msgs/Marker.h>

#include <Eigen/Geometry>
#include <string>

#include "fragg_map/sensor_model.h"

namespace fragg::ros {

/// `sensor` must be explicit (pinhole or spinning LiDAR, as resolveAutoSensor gives) with a
/// positive max range. Throws fragg::InvalidArgument otherwise.
visualization_msgs::Marker frustumMarker(const fragg::SensorModel& sensor,
                                         const Eigen::Isometry3d& T_map_sensor,
                                         const std::string& frame_id, const ::ros::Time& stamp,
                                         int segments = 24);

}  // namespace fragg::ros
