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
  return it == ids_.end() ? -1 : it->second.id;
}

CellMask cellMask(const fragg::Map& map, fragg::BlockIndex block, fragg::CellState state) {
  const fragg::OccupancyModel& model = map.model();
  const fragg::Cell* cells = map.blocks().block(block).cells;
  CellMask mask;
  for (int c = 0; c < fragg::kCellsPerBlock; ++c)
    if (model.state(cells[c]) == state) mask.set(c);
  return mask;
}

visualization_msgs::Marker blockMarker(const fragg::Map& map, fragg::BlockIndex block,
                                       const CellMask& cells, const MarkerStyle& style,
                                       const ros::Time& stamp, int32_t id) {
  visualization_msgs::Marker m = markerHeader(style, stamp, id, visualization_msgs::Marker::ADD);
  const double res_m = map.resolution();
  m.scale.x = m.scale.y = m.scale.z = res_m;
  m.color = heightColor(0.0, 0.0, 1.0, style.alpha);  // per-point colours below win
  const fragg::BlockKey key = map.blocks().meta(block).key;
  m.points.reserve(cells.count());
  m.colors.reserve(cells.count());
  // Colours depend on the height only: one per z layer of the block.
  std_msgs::ColorRGBA layer_color[fragg::kBlockSize];
  for (int z = 0; z < fragg::kBlockSize; ++z)
    layer_color[z] = heightColor((key.z * fragg::kBlockSize + z + 0.5) * res_m, style.color_min_z_m,
                                 style.color_max_z_m, style.alpha);
  for (int c = 0; c < fragg::kCellsPerBlock; ++c) {
    if (!cells.test(c)) continue;
    const fragg::VoxelKey v = fragg::voxelKeyOf(key, c);
    geometry_msgs::Point p;
    p.x = (v.x + 0.5) * res_m;
    p.y = (v.y + 0.5) * res_m;
    p.z = (v.z + 0.5) * res_m;
    m.points.push_back(p);
    m.colors.push_back(layer_color[c >> (2 * fragg::kBlockBits)]);
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
          markerHeader(style, stamp, it->second.id, visualization_msgs::Marker::DELETE));
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
    const CellMask cells = cellMask(map, i, style.state);
    const auto shown = ledger->ids_.find(key);
    if (shown == ledger->ids_.end()) {
      if (cells.none()) continue;
      const int32_t id = ledger->next_id_++;
      ledger->ids_.emplace(key, MarkerLedger::Shown{id, cells});
      out.markers.push_back(blockMarker(map, i, cells, style, stamp, id));
    } else if (cells.none()) {
      out.markers.push_back(
          markerHeader(style, stamp, shown->second.id, visualization_msgs::Marker::DELETE));
      ledger->ids_.erase(shown);
    } else if (cells != shown->second.cells) {
      shown->second.cells = cells;
      out.markers.push_back(blockMarker(map, i, cells, style, stamp, shown->second.id));
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
    const CellMask cells = cellMask(map, i, style.state);
    if (cells.none()) return;
    const int32_t id = ledger->next_id_++;
    ledger->ids_.emplace(blocks.meta(i).key, MarkerLedger::Shown{id, cells});
    out.markers.push_back(blockMarker(map, i, cells, style, stamp, id));
  });
  ledger->published_revision_ = map.revision();
  return out;
}

}  // namespace fragg_ros
