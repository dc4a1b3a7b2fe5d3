// colored_map: per-cell colours from the points' RGB, averaged as ColorOcTree does.
#include "fragg_map/ros/cell_colors.h"

#include <sensor_msgs/PointField.h>

#include <cmath>
#include <cstring>
#include <string>

#include "fragg_map/errors.h"

namespace fragg::ros {
namespace {

using sensor_msgs::PointField;

const PointField* fieldNamed(const sensor_msgs::PointCloud2& msg, const char* name) {
  for (const PointField& f : msg.fields)
    if (f.name == name) return &f;
  return nullptr;
}

const PointField* rgbField(const sensor_msgs::PointCloud2& msg) {
  const PointField* f = fieldNamed(msg, "rgb");
  return f ? f : fieldNamed(msg, "rgba");
}

double readCoordinate(const uint8_t* p, uint8_t datatype) {
  if (datatype == PointField::FLOAT64) {
    double d;
    std::memcpy(&d, p, 8);
    return d;
  }
  float f;
  std::memcpy(&f, p, 4);
  return f;
}

}  // namespace

bool hasRgbField(const sensor_msgs::PointCloud2& msg) { return rgbField(msg) != nullptr; }

size_t CellColors::integrate(const sensor_msgs::PointCloud2& msg,
                             const Eigen::Isometry3d& T_map_sensor, double max_range_m,
                             const fragg::Map& map) {
  const PointField* rgb = rgbField(msg);
  if (!rgb) return 0;
  if (rgb->datatype != PointField::FLOAT32 && rgb->datatype != PointField::UINT32 &&
      rgb->datatype != PointField::INT32)
    throw fragg::InvalidArgument("field '" + rgb->name + "' has datatype " +
                                 std::to_string(rgb->datatype) +
                                 ", expected FLOAT32, UINT32 or INT32 (packed colour)");
  if (uint64_t{rgb->offset} + 4 > msg.point_step)
    throw fragg::InvalidArgument("field '" + rgb->name + "' ends past point_step");
  const PointField* axis[3] = {fieldNamed(msg, "x"), fieldNamed(msg, "y"), fieldNamed(msg, "z")};
  for (const PointField* f : axis) {
    // The insertion validated the cloud already; a missing or odd axis gives no colours.
    if (!f || (f->datatype != PointField::FLOAT32 && f->datatype != PointField::FLOAT64) ||
        uint64_t{f->offset} + (f->datatype == PointField::FLOAT64 ? 8 : 4) > msg.point_step)
      return 0;
  }
  if (size_t{msg.row_step} * msg.height > msg.data.size() ||
      size_t{msg.point_step} * msg.width > msg.row_step)
    return 0;
  const fragg::HeightFilterParams& band = map.params().height_filter;
  const Eigen::Vector3d origin_map = T_map_sensor.translation();
  const uint64_t sequence = sequence_ + 1;
  size_t used = 0;
  for (uint32_t row = 0; row < msg.height; ++row) {
    for (uint32_t col = 0; col < msg.width; ++col) {
      const uint8_t* p =
          msg.data.data() + size_t{row} * msg.row_step + size_t{col} * msg.point_step;
      const Eigen::Vector3d p_sensor(readCoordinate(p + axis[0]->offset, axis[0]->datatype),
                                     readCoordinate(p + axis[1]->offset, axis[1]->datatype),
                                     readCoordinate(p + axis[2]->offset, axis[2]->datatype));
      if (!p_sensor.allFinite()) continue;
      const Eigen::Vector3d p_map = T_map_sensor * p_sensor;
      if (max_range_m > 0.0 && (p_map - origin_map).norm() > max_range_m) continue;
      if (p_map.z() < band.min_z_m || p_map.z() > band.max_z_m) continue;
      uint32_t packed;
      std::memcpy(&packed, p + rgb->offset, 4);
      const Rgb8 c{static_cast<uint8_t>((packed >> 16) & 0xff),
                   static_cast<uint8_t>((packed >> 8) & 0xff), static_cast<uint8_t>(packed & 0xff)};
      const fragg::VoxelKey v = map.keyOf(p_map);
      BlockColors& block = blocks_[fragg::blockKeyOf(v)];
      block.recolored_at = sequence;
      const uint16_t index = static_cast<uint16_t>(fragg::cellIndexOf(v));
      bool found = false;
      for (auto& [i, colour] : block.cells) {
        if (i != index) continue;
        colour.r = static_cast<uint8_t>((colour.r + c.r) / 2);
        colour.g = static_cast<uint8_t>((colour.g + c.g) / 2);
        colour.b = static_cast<uint8_t>((colour.b + c.b) / 2);
        found = true;
        break;
      }
      if (!found) block.cells.emplace_back(index, c);
      ++used;
    }
  }
  if (used) sequence_ = sequence;
  return used;
}

std::optional<Rgb8> CellColors::find(const fragg::VoxelKey& v) const {
  const auto it = blocks_.find(fragg::blockKeyOf(v));
  if (it == blocks_.end()) return std::nullopt;
  const uint16_t index = static_cast<uint16_t>(fragg::cellIndexOf(v));
  for (const auto& [i, colour] : it->second.cells)
    if (i == index) return colour;
  return std::nullopt;
}

std::vector<fragg::BlockKey> CellColors::recoloredSince(uint64_t sequence) const {
  std::vector<fragg::BlockKey> out;
  if (sequence >= sequence_) return out;
  for (const auto& [key, block] : blocks_)
    if (block.recolored_at > sequence) out.push_back(key);
  return out;
}

void CellColors::prune(const fragg::Map& map) {
  const fragg::BlockView view = map.blockView();
  for (auto it = blocks_.begin(); it != blocks_.end();) {
    const fragg::Block* b = view.findBlock(it->first);
    auto& cells = it->second.cells;
    if (b) {
      for (size_t i = 0; i < cells.size();) {
        if (b->cells[cells[i].first].observed()) {
          ++i;
        } else {
          cells[i] = cells.back();
          cells.pop_back();
        }
      }
    }
    if (!b || cells.empty())
      it = blocks_.erase(it);
    else
      ++it;
  }
}

size_t CellColors::cells() const {
  size_t n = 0;
  for (const auto& [key, block] : blocks_) n += block.cells.size();
  return n;
}

}  // namespace fragg::ros
