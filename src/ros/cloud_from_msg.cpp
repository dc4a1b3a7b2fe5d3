// sensor_msgs/PointCloud2 -> fragg::PointCloud: validation, packed float32 fast path and a
// strided reader for every other layout.
#include "fragg_map/ros/cloud_from_msg.h"

#include <sensor_msgs/PointField.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "fragg_map/errors.h"

namespace fragg::ros {
namespace {

using sensor_msgs::PointField;

constexpr bool kHostBigEndian = __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__;

[[noreturn]] void reject(const std::string& problem) {
  throw fragg::InvalidArgument("malformed PointCloud2: " + problem);
}

struct XyzFields {
  const PointField* axis[3] = {nullptr, nullptr, nullptr};
};

// Finds x, y, z and checks their types and extents against point_step.
XyzFields findXyz(const sensor_msgs::PointCloud2& msg) {
  static const char* const kNames[3] = {"x", "y", "z"};
  XyzFields xyz;
  for (const PointField& field : msg.fields)
    for (int a = 0; a < 3; ++a)
      if (field.name == kNames[a]) xyz.axis[a] = &field;
  for (int a = 0; a < 3; ++a) {
    const PointField* f = xyz.axis[a];
    if (!f) reject(std::string("no '") + kNames[a] + "' field");
    if (f->datatype != PointField::FLOAT32 && f->datatype != PointField::FLOAT64)
      reject(std::string("field '") + kNames[a] + "' has datatype " + std::to_string(f->datatype) +
             ", expected FLOAT32 (7) or FLOAT64 (8)");
    if (f->count != 1)
      reject(std::string("field '") + kNames[a] + "' has count " + std::to_string(f->count) +
             ", expected 1");
    const uint64_t end = uint64_t{f->offset} + (f->datatype == PointField::FLOAT32 ? 4 : 8);
    if (end > msg.point_step)
      reject(std::string("field '") + kNames[a] + "' ends at byte " + std::to_string(end) +
             ", past point_step " + std::to_string(msg.point_step));
  }
  return xyz;
}

void checkExtent(const sensor_msgs::PointCloud2& msg) {
  const uint64_t width = msg.width, height = msg.height;
  if (width == 0 || height == 0)
    reject("0 points (width " + std::to_string(width) + ", height " + std::to_string(height) + ")");
  if (uint64_t{msg.row_step} < width * msg.point_step)
    reject("row_step " + std::to_string(msg.row_step) + " < width " + std::to_string(width) +
           " x point_step " + std::to_string(msg.point_step));
  const uint64_t needed = (height - 1) * msg.row_step + width * msg.point_step;
  if (needed > msg.data.size())
    reject("data has " + std::to_string(msg.data.size()) + " bytes, " + std::to_string(needed) +
           " needed for " + std::to_string(width) + " x " + std::to_string(height) + " points of " +
           std::to_string(msg.point_step) + " bytes");
}

bool isPackedFloat32(const sensor_msgs::PointCloud2& msg, const XyzFields& xyz) {
  if (bool(msg.is_bigendian) != kHostBigEndian) return false;
  for (int a = 0; a < 3; ++a)
    if (xyz.axis[a]->datatype != PointField::FLOAT32 || xyz.axis[a]->offset != 4u * a) return false;
  return true;
}

void copyPackedFloat32(const sensor_msgs::PointCloud2& msg, fragg::PointCloud& cloud) {
  static_assert(sizeof(Eigen::Vector3f) == 12, "Vector3f is three packed floats");
  const size_t width = msg.width, height = msg.height;
  auto* out = reinterpret_cast<uint8_t*>(cloud.points_S.data());
  if (msg.point_step == 12 && msg.row_step == 12 * width) {
    std::memcpy(out, msg.data.data(), 12 * width * height);
    return;
  }
  for (size_t row = 0; row < height; ++row) {
    const uint8_t* in = msg.data.data() + row * msg.row_step;
    uint8_t* dst = out + 12 * row * width;
    for (size_t col = 0; col < width; ++col, in += msg.point_step, dst += 12)
      std::memcpy(dst, in, 12);
  }
}

template <typename T>
float loadField(const uint8_t* p, bool swap) {
  uint8_t bytes[sizeof(T)];
  std::memcpy(bytes, p, sizeof(T));
  if (swap) std::reverse(bytes, bytes + sizeof(T));
  T v;
  std::memcpy(&v, bytes, sizeof(T));
  return static_cast<float>(v);
}

void copyStrided(const sensor_msgs::PointCloud2& msg, const XyzFields& xyz,
                 fragg::PointCloud& cloud) {
  const bool swap = bool(msg.is_bigendian) != kHostBigEndian;
  const size_t width = msg.width, height = msg.height;
  uint32_t offset[3];
  bool is_double[3];
  for (int a = 0; a < 3; ++a) {
    offset[a] = xyz.axis[a]->offset;
    is_double[a] = xyz.axis[a]->datatype == PointField::FLOAT64;
  }
  for (size_t row = 0; row < height; ++row) {
    const uint8_t* in = msg.data.data() + row * msg.row_step;
    Eigen::Vector3f* out = cloud.points_S.data() + row * width;
    for (size_t col = 0; col < width; ++col, in += msg.point_step, ++out)
      for (int a = 0; a < 3; ++a)
        (*out)[a] = is_double[a] ? loadField<double>(in + offset[a], swap)
                                 : loadField<float>(in + offset[a], swap);
  }
}

}  // namespace

fragg::PointCloud cloudFromMsg(const sensor_msgs::PointCloud2& msg, CloudLayout* layout) {
  fragg::PointCloud cloud;
  cloudFromMsg(msg, &cloud, layout);
  return cloud;
}

void cloudFromMsg(const sensor_msgs::PointCloud2& msg, fragg::PointCloud* out,
                  CloudLayout* layout) {
  const XyzFields xyz = findXyz(msg);
  checkExtent(msg);
  fragg::PointCloud& cloud = *out;
  cloud.width = 0;
  cloud.height = 1;
  cloud.free_only.clear();
  cloud.points_S.resize(size_t{msg.width} * msg.height);  // within its capacity: no new buffer
  const bool packed = isPackedFloat32(msg, xyz);
  if (packed)
    copyPackedFloat32(msg, cloud);
  else
    copyStrided(msg, xyz, cloud);
  if (layout) *layout = packed ? CloudLayout::kPackedFloat32 : CloudLayout::kStrided;
  if (msg.height > 1) {
    cloud.width = msg.width;
    cloud.height = msg.height;
  }
  // Not a layout fault: a well-formed cloud whose every point is NaN or Inf (a sensor that saw
  // nothing in range). Its own message, without "malformed".
  if (finitePointCount(cloud) == 0)
    throw fragg::InvalidArgument("PointCloud2 without a usable point: no finite point among " +
                                 std::to_string(cloud.size()) + " (all NaN or Inf)");
}

size_t finitePointCount(const fragg::PointCloud& cloud) {
  return static_cast<size_t>(std::count_if(cloud.points_S.begin(), cloud.points_S.end(),
                                           [](const Eigen::Vector3f& p) { return p.allFinite(); }));
}

}  // namespace fragg::ros
