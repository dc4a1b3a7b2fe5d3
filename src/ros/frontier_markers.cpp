// Frontier clusters, viewpoints and cells as MarkerArray and PointCloud2, bounded in size.
#include "fragg_map/ros/frontier_markers.h"

#include <algorithm>
#include <cmath>

#include "fragg_map/errors.h"
#include "fragg_map/ros/occupied_cloud.h"

namespace fragg::ros {
namespace {

using visualization_msgs::Marker;

geometry_msgs::Point centreOf(const VoxelKey& k, double resolution_m) {
  geometry_msgs::Point p;
  p.x = (k.x + 0.5) * resolution_m;
  p.y = (k.y + 0.5) * resolution_m;
  p.z = (k.z + 0.5) * resolution_m;
  return p;
}

std_msgs::ColorRGBA rgba(double r, double g, double b, double a) {
  std_msgs::ColorRGBA c;
  c.r = static_cast<float>(r);
  c.g = static_cast<float>(g);
  c.b = static_cast<float>(b);
  c.a = static_cast<float>(a);
  return c;
}

// HSV (s = v = 1) to RGB, hue in [0, 1).
std_msgs::ColorRGBA hue(double h) {
  const double x = 6.0 * (h - std::floor(h));
  const int sector = std::min(static_cast<int>(x), 5);
  const double f = x - sector;
  switch (sector) {
    case 0:
      return rgba(1, f, 0, 1);
    case 1:
      return rgba(1 - f, 1, 0, 1);
    case 2:
      return rgba(0, 1, f, 1);
    case 3:
      return rgba(0, 1 - f, 1, 1);
    case 4:
      return rgba(f, 0, 1, 1);
    default:
      return rgba(1, 0, 1 - f, 1);
  }
}

}  // namespace

uint64_t subsampleStride(uint64_t cells, uint64_t max_cells) {
  if (cells == 0 || cells <= max_cells) return 1;
  if (max_cells == 0) return 0;
  return (cells + max_cells - 1) / max_cells;
}

std_msgs::ColorRGBA clusterColor(uint64_t id) {
  constexpr double kGolden = 0.6180339887498949;
  return hue(static_cast<double>(id % 1000003) * kGolden);
}

visualization_msgs::MarkerArray frontierMarkers(const FrontierMarkerInput& in,
                                                const std::string& frame_id,
                                                const ::ros::Time& stamp, uint64_t max_cells,
                                                uint64_t* cells_drawn) {
  if (!in.clusters) throw fragg::InvalidArgument("frontier markers: no clusters given");
  if (!(in.resolution_m > 0.0))
    throw fragg::InvalidArgument("frontier markers: the resolution must be > 0");
  if (in.views && !in.views->empty() && in.views->size() != in.clusters->size())
    throw fragg::InvalidArgument("frontier markers: " + std::to_string(in.views->size()) +
                                 " viewpoint lists for " + std::to_string(in.clusters->size()) +
                                 " clusters");
  visualization_msgs::MarkerArray out;
  Marker clear;
  clear.header.frame_id = frame_id;
  clear.header.stamp = stamp;
  clear.action = Marker::DELETEALL;
  out.markers.push_back(clear);

  uint64_t total = 0;
  for (const auto& c : *in.clusters) total += c.cells.size();
  const uint64_t stride = subsampleStride(total, max_cells);
  uint64_t drawn = 0, index = 0;
  for (const planning::FrontierCluster& c : *in.clusters) {
    Marker m;
    m.header = clear.header;
    m.ns = "frontier_cells";
    m.id = static_cast<int32_t>(c.id);
    m.type = Marker::CUBE_LIST;
    m.action = Marker::ADD;
    m.pose.orientation.w = 1.0;
    m.scale.x = m.scale.y = m.scale.z = in.resolution_m;
    m.color = clusterColor(c.id);
    for (const VoxelKey& k : c.cells) {
      if (stride != 0 && index++ % stride == 0) m.points.push_back(centreOf(k, in.resolution_m));
    }
    drawn += m.points.size();
    if (!m.points.empty()) out.markers.push_back(std::move(m));
  }
  if (cells_drawn) *cells_drawn = drawn;

  if (!in.views || in.views->empty()) return out;
  double lo = INFINITY, hi = -INFINITY;
  for (const auto& vs : *in.views)
    for (const auto& v : vs) lo = std::min(lo, v.gain_bits), hi = std::max(hi, v.gain_bits);
  int32_t id = 0;
  for (const auto& vs : *in.views)
    for (const auto& v : vs) {
      Marker m;
      m.header = clear.header;
      m.ns = "viewpoints";
      m.id = id++;
      m.type = Marker::ARROW;
      m.action = Marker::ADD;
      m.pose.position.x = v.position_m.x();
      m.pose.position.y = v.position_m.y();
      m.pose.position.z = v.position_m.z();
      m.pose.orientation.z = std::sin(0.5 * v.yaw_rad);
      m.pose.orientation.w = std::cos(0.5 * v.yaw_rad);
      m.scale.x = 0.6;  // arrow length, shaft and head widths [m]
      m.scale.y = 0.08;
      m.scale.z = 0.12;
      const double t = hi > lo ? (v.gain_bits - lo) / (hi - lo) : 1.0;
      m.color = rgba(1.0 - t, t, 0.1, 1.0);
      out.markers.push_back(std::move(m));
    }
  return out;
}

sensor_msgs::PointCloud2 frontierCloud(const std::vector<VoxelKey>& cells, double resolution_m,
                                       const std::string& frame_id, const ::ros::Time& stamp,
                                       uint64_t max_cells) {
  const uint64_t stride = subsampleStride(cells.size(), max_cells);
  std::vector<float> xyz;
  if (stride != 0) {
    xyz.reserve(3 * ((cells.size() + stride - 1) / stride));
    for (size_t i = 0; i < cells.size(); i += stride) {
      const geometry_msgs::Point p = centreOf(cells[i], resolution_m);
      xyz.insert(xyz.end(),
                 {static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)});
    }
  }
  return packedXyzCloud(xyz, frame_id, stamp);
}

}  // namespace fragg::ros
