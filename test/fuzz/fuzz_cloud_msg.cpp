// sensor_msgs/PointCloud2 as it arrives on the wire: the bytes are deserialised with
// ros::serialization (as roscpp does before the server's callback) and handed to cloudFromMsg.
// Inputs that are not a whole message are dropped before the converter, as roscpp drops them;
// the two length-prefixed arrays are checked against the bytes left first, because roscpp's
// deserialiser sizes them from the prefix alone (a 12-byte input could ask for 4 GiB).
#include <ros/serialization.h>
#include <sensor_msgs/PointCloud2.h>

#include "fragg_map/errors.h"
#include "fragg_map/ros/cloud_from_msg.h"
#include "fuzz_targets.h"

namespace fragg::fuzz {
namespace {

namespace ser = ::ros::serialization;

// False when the bytes are not one whole PointCloud2 message.
bool deserialise(const uint8_t* data, size_t size, sensor_msgs::PointCloud2& msg) {
  ser::IStream in(const_cast<uint8_t*>(data), static_cast<uint32_t>(size));
  try {
    ser::deserialize(in, msg.header);
    ser::deserialize(in, msg.height);
    ser::deserialize(in, msg.width);
    uint32_t field_count;
    ser::deserialize(in, field_count);
    constexpr uint32_t kMinFieldBytes = 4 + 4 + 1 + 4;  // empty name, offset, datatype, count
    if (field_count > in.getLength() / kMinFieldBytes) return false;
    msg.fields.resize(field_count);
    for (auto& field : msg.fields) ser::deserialize(in, field);
    ser::deserialize(in, msg.is_bigendian);
    ser::deserialize(in, msg.point_step);
    ser::deserialize(in, msg.row_step);
    uint32_t data_bytes;
    ser::deserialize(in, data_bytes);
    if (data_bytes > in.getLength()) return false;
    msg.data.assign(in.getData(), in.getData() + data_bytes);
    in.advance(data_bytes);
    ser::deserialize(in, msg.is_dense);
  } catch (const ser::StreamOverrunException&) {
    return false;
  }
  return in.getLength() == 0;
}

}  // namespace

bool cloudMsg(const uint8_t* data, size_t size) {
  if (size > UINT32_MAX) return false;
  sensor_msgs::PointCloud2 msg;
  if (!deserialise(data, size, msg)) return false;
  try {
    ros::CloudLayout layout;
    const PointCloud cloud = ros::cloudFromMsg(msg, &layout);
    ros::finitePointCount(cloud);
    return true;
  } catch (const IoError&) {
  } catch (const InvalidArgument&) {
  }
  return false;
}

}  // namespace fragg::fuzz
