// A Velodyne-like sensor_msgs/PointCloud2 (x y z intensity float32, point_step 16) from a cloud:
// what the server benchmarks feed the map server's conversion.
#pragma once

#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/PointField.h>

#include <cstring>

#include "fragg_map/point_cloud.h"

namespace fragg::bench {

inline sensor_msgs::PointCloud2 velodyneLikeMsg(const fragg::PointCloud& cloud) {
  sensor_msgs::PointCloud2 msg;
  msg.header.frame_id = "lidar";
  msg.width = cloud.organised() ? cloud.width : static_cast<uint32_t>(cloud.size());
  msg.height = cloud.organised() ? cloud.height : 1;
  const char* names[4] = {"x", "y", "z", "intensity"};
  for (uint32_t i = 0; i < 4; ++i) {
    sensor_msgs::PointField f;
    f.name = names[i];
    f.offset = 4 * i;
    f.datatype = sensor_msgs::PointField::FLOAT32;
    f.count = 1;
    msg.fields.push_back(f);
  }
  msg.point_step = 16;
  msg.row_step = 16 * msg.width;
  msg.data.assign(size_t{msg.row_step} * msg.height, 0);
  for (size_t i = 0; i < cloud.size(); ++i)
    std::memcpy(&msg.data[16 * i], cloud.points_S[i].data(), 12);
  return msg;
}

}  // namespace fragg::bench
