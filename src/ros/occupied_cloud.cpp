// Occupied voxel centres as a packed float32 PointCloud2.
#include "fragg_map/ros/occupied_cloud.h"

#include <sensor_msgs/PointField.h>

#include <cstring>
#include <vector>

#include "fragg_map/ros/speckles.h"

namespace fragg::ros {

sensor_msgs::PointCloud2 packedXyzCloud(const std::vector<float>& xyz, const std::string& frame_id,
                                        const ::ros::Time& stamp) {
  sensor_msgs::PointCloud2 msg;
  msg.header.frame_id = frame_id;
  msg.header.stamp = stamp;
  msg.height = 1;
  msg.width = static_cast<uint32_t>(xyz.size() / 3);
  static const char* const kNames[3] = {"x", "y", "z"};
  for (uint32_t a = 0; a < 3; ++a) {
    sensor_msgs::PointField f;
    f.name = kNames[a];
    f.offset = 4 * a;
    f.datatype = sensor_msgs::PointField::FLOAT32;
    f.count = 1;
    msg.fields.push_back(f);
  }
  msg.is_bigendian = __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__;
  msg.point_step = 12;
  msg.row_step = 12 * msg.width;
  msg.is_dense = true;
  msg.data.resize(xyz.size() * sizeof(float));
  if (!xyz.empty()) std::memcpy(msg.data.data(), xyz.data(), msg.data.size());
  return msg;
}

sensor_msgs::PointCloud2 occupiedCloud(const fragg::Map& map, const std::string& frame_id,
                                       const ::ros::Time& stamp, bool hide_speckles,
                                       const HeightBand& heights) {
  heights.validate();
  std::vector<float> xyz;
  const fragg::BlockView blocks = map.blockView();
  map.forEachBlock([&](const fragg::BlockKey& key, const fragg::Block& b) {
    for (int c = 0; c < fragg::kCellsPerBlock; ++c) {
      if (map.state(b.cells[c]) != fragg::CellState::kOccupied) continue;
      const fragg::VoxelKey v = fragg::voxelKeyOf(key, c);
      if (!heights.showsLayer(v.z, map.resolution())) continue;
      if (hide_speckles && isSpeckle(map, blocks, v)) continue;
      const Eigen::Vector3d p_map = map.centerOf(v);
      xyz.insert(xyz.end(), {static_cast<float>(p_map.x()), static_cast<float>(p_map.y()),
                             static_cast<float>(p_map.z())});
    }
  });
  return packedXyzCloud(xyz, frame_id, stamp);
}

}  // namespace fragg::ros
