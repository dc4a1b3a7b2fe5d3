// ROS bag reader (built only with ROS, in the fragg_map_rosbag library). The header itself is
// ROS-free so that tools can call registerRosbagReader() under #ifdef FRAGG_HAVE_ROSBAG.
#pragma once

#include <memory>
#include <string>

#include "fragg_map/io/dataset.h"

namespace fragg {

/// Scans from sensor_msgs/PointCloud2 messages of a bag: the topic is options.topic, or the
/// only PointCloud2 topic of the bag (more than one: IoError listing them). x y z as float32
/// or float64, organised clouds kept with their NaNs. T_map_sensor = the transform
/// options.frame <- cloud frame at the cloud's stamp, from every /tf and /tf_static message of
/// the bag; clouds without that transform are skipped and counted (ScanSource::skipped()).
std::unique_ptr<ScanSource> openRosbag(const std::string& path, const DatasetOptions& options);

/// Makes openDataset read .bag files with openRosbag (registerBagOpener(openRosbag)).
void registerRosbagReader();

}  // namespace fragg
