// Builds sensor_msgs/PointCloud2 messages of any layout for the converter tests.
#pragma once

#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/PointField.h>

#include <Eigen/Core>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace fragg::ros::test {

struct FieldSpec {
  std::string name;
  uint32_t offset;
  uint8_t datatype;
};

inline size_t fieldBytes(uint8_t datatype) {
  switch (datatype) {
    case sensor_msgs::PointField::INT8:
    case sensor_msgs::PointField::UINT8:
      return 1;
    case sensor_msgs::PointField::INT16:
    case sensor_msgs::PointField::UINT16:
      return 2;
    case sensor_msgs::PointField::FLOAT64:
      return 8;
    default:
      return 4;
  }
}

/// A cloud of `points` (row-major, width x height) with the given fields; x, y, z fields get
/// the point's coordinates in their datatype, other fields get zeros. `row_padding` bytes are
/// added at the end of every row.
inline sensor_msgs::PointCloud2 makeCloud(const std::vector<Eigen::Vector3f>& points,
                                          uint32_t width, uint32_t height,
                                          const std::vector<FieldSpec>& fields, uint32_t point_step,
                                          uint32_t row_padding = 0) {
  sensor_msgs::PointCloud2 msg;
  msg.header.frame_id = "sensor";
  msg.width = width;
  msg.height = height;
  msg.point_step = point_step;
  msg.row_step = width * point_step + row_padding;
  msg.is_bigendian = false;
  for (const FieldSpec& f : fields) {
    sensor_msgs::PointField pf;
    pf.name = f.name;
    pf.offset = f.offset;
    pf.datatype = f.datatype;
    pf.count = 1;
    msg.fields.push_back(pf);
  }
  msg.data.assign(size_t{msg.row_step} * height, 0);
  for (uint32_t row = 0; row < height; ++row)
    for (uint32_t col = 0; col < width; ++col) {
      const Eigen::Vector3f& p = points[size_t{row} * width + col];
      uint8_t* rec = msg.data.data() + size_t{row} * msg.row_step + size_t{col} * point_step;
      for (const FieldSpec& f : fields) {
        const int axis = f.name == "x" ? 0 : f.name == "y" ? 1 : f.name == "z" ? 2 : -1;
        if (axis < 0) continue;
        if (f.datatype == sensor_msgs::PointField::FLOAT64) {
          const double v = p[axis];
          std::memcpy(rec + f.offset, &v, 8);
        } else if (f.datatype == sensor_msgs::PointField::FLOAT32) {
          std::memcpy(rec + f.offset, &p[axis], 4);
        } else if (f.datatype == sensor_msgs::PointField::INT16) {
          const int16_t v = static_cast<int16_t>(p[axis]);
          std::memcpy(rec + f.offset, &v, 2);
        }
      }
    }
  return msg;
}

inline std::vector<FieldSpec> packedXyz() {
  using F = sensor_msgs::PointField;
  return {{"x", 0, F::FLOAT32}, {"y", 4, F::FLOAT32}, {"z", 8, F::FLOAT32}};
}

}  // namespace fragg::ros::test
