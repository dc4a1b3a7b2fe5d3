// One CUBE_LIST marker per block; incremental updates from BlockMeta::changed_at.
#include "fragg_map/ros/block_markers.h"

#include <vector>

#include "fragg_map/ros/height_color.h"

namespace fragg_ros {
namespace {

visualization_msgs::Marker markerHeader(const MarkerStyle& style, const ros::Time& stamp,
                                        int32_t id, int32_t action) {
  visualization_msgs::Marker m;
  m.header.frame_id = style.frame_id;
  m.header.stamp = stamp;
  m.ns = style.ns;
  m.id = id;
  m.type = visualization_msgs::Marker::CUBE_LIST;
  m.action = action;
  m.pose.orientation.w = 1.0;
  return m;
}

}  // namespace

int32_t MarkerLedger::idOf(const fragg::BlockKey& key) const {
  const auto it = ids_.find(key);
  return it == ids_.end() ? -1 : it->second;
}

visualization_msgs::Marker blockMarker(const fragg::Map& map, fragg::BlockIndex block,
                                       const MarkerStyle& style, const ros::Time& stamp,
                                       int32_t id) {
  visualization_msgs::Marker m = markerHeader(style, stamp, id, visualization_msgs::Marker::ADD);
  const double res_m = map.resolution();
  m.scale.x = m.scale.y = m.scale.z = res_m;
  m.color = heightColor(0.0, 0.0, 1.0, style.alpha);  // per-point colours below win
  const fragg::BlockMap& blocks = map.blocks();
  const fragg::BlockKey key = blocks.meta(block).key;
  const fragg::Block& b = blocks.block(block);
  for (int c = 0; c < fragg::kCellsPerBlock; ++c) {
    if (map.state(b.cells[c]) != style.state) continue;
    const Eigen::Vector3d p_map = map.centerOf(fragg::voxelKeyOf(key, c));
    geometry_msgs::Point p;
    p.x = p_map.x();
    p.y = p_map.y();
    p.z = p_map.z();
    m.points.push_back(p);
    m.colors.push_back(heightColor(p.z, style.color_min_z_m, style.color_max_z_m, style.alpha));
  }
  return m;
}

visualization_msgs::MarkerArray changedBlockMarkers(const fragg::Map& map, const MarkerStyle& style,
                                                    const ros::Time& stamp, MarkerLedger* ledger) {
  visualization_msgs::MarkerArray out;
  const fragg::BlockMap& blocks = map.blocks();
  const uint64_t since = ledger->published_revision_;
  // Shown blocks that were erased (clearBox, reset) have no metadata left: look them up.
  for (auto it = ledger->ids_.begin(); it != ledger->ids_.end();) {
    if (blocks.find(it->first) == fragg::kNoBlock) {
      out.markers.push_back(
          markerHeader(style, stamp, it->second, visualization_msgs::Marker::DELETE));
      it = ledger->ids_.erase(it);
    } else {
      ++it;
    }
  }
  std::vector<fragg::BlockIndex> changed;
  blocks.forEach([&](fragg::BlockIndex i) {
    if (blocks.meta(i).changed_at > since) changed.push_back(i);
  });
  for (fragg::BlockIndex i : changed) {
    const fragg::BlockKey key = blocks.meta(i).key;
    const auto shown = ledger->ids_.find(key);
    const int32_t id = shown != ledger->ids_.end() ? shown->second : ledger->next_id_;
    visualization_msgs::Marker m = blockMarker(map, i, style, stamp, id);
    if (!m.points.empty()) {
      if (shown == ledger->ids_.end()) ledger->ids_.emplace(key, ledger->next_id_++);
      out.markers.push_back(std::move(m));
    } else if (shown != ledger->ids_.end()) {
      out.markers.push_back(markerHeader(style, stamp, id, visualization_msgs::Marker::DELETE));
      ledger->ids_.erase(shown);
    }
  }
  ledger->published_revision_ = map.revision();
  return out;
}

visualization_msgs::MarkerArray allBlockMarkers(const fragg::Map& map, const MarkerStyle& style,
                                                const ros::Time& stamp, MarkerLedger* ledger) {
  visualization_msgs::MarkerArray out;
  out.markers.push_back(markerHeader(style, stamp, 0, visualization_msgs::Marker::DELETEALL));
  ledger->ids_.clear();
  ledger->next_id_ = 0;
  const fragg::BlockMap& blocks = map.blocks();
  blocks.forEach([&](fragg::BlockIndex i) {
    visualization_msgs::Marker m = blockMarker(map, i, style, stamp, ledger->next_id_);
    if (m.points.empty()) return;
    ledger->ids_.emplace(blocks.meta(i).key, ledger->next_id_++);
    out.markers.push_back(std::move(m));
  });
  ledger->published_revision_ = map.revision();
  return out;
}

}  // namespace fragg_ros
