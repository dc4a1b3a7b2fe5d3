// One CUBE_LIST marker per block; incremental updates from Map::changedBlocksSince (which
// cells are occupied, for occupied markers; any change for the others).
#include "fragg_map/ros/block_markers.h"

#include <optional>
#include <unordered_set>
#include <vector>

#include "fragg_map/ros/height_color.h"
#include "fragg_map/ros/layer_masks.h"
#include "fragg_map/ros/speckles.h"

namespace fragg::ros {
namespace {

visualization_msgs::Marker markerHeader(const MarkerStyle& style, const ::ros::Time& stamp,
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

CellMask cellMask(const fragg::Map& map, const fragg::Block& block, fragg::CellState state) {
  // One 64-cell word at a time (the hot loop of an incremental update: every changed block is
  // scanned; layer_masks.h). Unobserved cells hold INT16_MIN, below every threshold.
  const fragg::OccupancyModel& model = map.model();
  const fragg::Cell* cells = block.cells;
  CellMask mask;
  for (int w = 0; w < fragg::kCellsPerBlock / 64; ++w) {
    const fragg::Cell* c = cells + 64 * w;
    uint64_t word = 0;
    switch (state) {
      case fragg::CellState::kOccupied:
        word = layerMasks(c, model.occupied_above_fx, model.free_below_fx).occupied;
        break;
      case fragg::CellState::kFree:
        word = layerMasks(c, model.occupied_above_fx, model.free_below_fx).free;
        break;
      default:
        for (int i = 0; i < 64; ++i)
          word |= uint64_t{model.state(c[i]) == fragg::CellState::kUnknown} << i;
    }
    if (word) mask |= CellMask(word) << (64 * w);
  }
  return mask;
}

CellMask drawnCells(const fragg::Map& map, const fragg::BlockView& blocks,
                    const fragg::BlockKey& key, const fragg::Block& block,
                    const MarkerStyle& style) {
  CellMask cells = cellMask(map, block, style.state);
  if (!style.heights.unbounded()) {
    const uint8_t layers = style.heights.blockLayers(key.z, map.resolution());
    CellMask shown;
    for (int z = 0; z < fragg::kBlockSize; ++z)
      if (layers >> z & 1) shown |= CellMask(~uint64_t{0}) << (64 * z);
    cells &= shown;
  }
  if (style.hide_speckles && cells.any()) cells = withoutSpeckles(map, blocks, key, cells);
  return cells;
}

visualization_msgs::Marker blockMarker(const fragg::Map& map, const fragg::BlockKey& key,
                                       const CellMask& cells, const MarkerStyle& style,
                                       const ::ros::Time& stamp, int32_t id) {
  visualization_msgs::Marker m = markerHeader(style, stamp, id, visualization_msgs::Marker::ADD);
  const double res_m = map.resolution();
  m.scale.x = m.scale.y = m.scale.z = res_m;
  m.color = heightColor(0.0, 0.0, 1.0, style.alpha);  // per-point colours below win
  m.points.reserve(cells.count());
  m.colors.reserve(cells.count());
  // Colours depend on the height only: one per z layer of the block.
  std_msgs::ColorRGBA layer_color[fragg::kBlockSize];
  for (int z = 0; z < fragg::kBlockSize; ++z) {
    if (style.height_colors) {
      layer_color[z] = heightColor((key.z * fragg::kBlockSize + z + 0.5) * res_m,
                                   style.color_min_z_m, style.color_max_z_m, style.alpha);
    } else {
      layer_color[z].r = style.flat_rgb[0];
      layer_color[z].g = style.flat_rgb[1];
      layer_color[z].b = style.flat_rgb[2];
      layer_color[z].a = style.alpha;
    }
  }
  for (int c = 0; c < fragg::kCellsPerBlock; ++c) {
    if (!cells.test(c)) continue;
    const fragg::VoxelKey v = fragg::voxelKeyOf(key, c);
    geometry_msgs::Point p;
    p.x = (v.x + 0.5) * res_m;
    p.y = (v.y + 0.5) * res_m;
    p.z = (v.z + 0.5) * res_m;
    m.points.push_back(p);
    m.colors.push_back(layer_color[c >> (2 * fragg::kBlockBits)]);
    if (style.colors) {
      if (const std::optional<Rgb8> rgb = style.colors->find(v)) {
        m.colors.back().r = rgb->r / 255.0f;
        m.colors.back().g = rgb->g / 255.0f;
        m.colors.back().b = rgb->b / 255.0f;
      }
    }
  }
  return m;
}

visualization_msgs::MarkerArray changedBlockMarkers(const fragg::Map& map, const MarkerStyle& style,
                                                    const ::ros::Time& stamp,
                                                    MarkerLedger* ledger) {
  visualization_msgs::MarkerArray out;
  const fragg::BlockView blocks = map.blockView();
  const uint64_t since = ledger->published_revision_;
  // Shown blocks that were erased (clearBox, reset, paged out) are not listed as changed: look
  // them up, when the map's view changed since the last update (no erase without that).
  const bool view_moved = map.viewEpoch() != ledger->view_epoch_;
  for (auto it = ledger->ids_.begin(); view_moved && it != ledger->ids_.end();) {
    if (!blocks.findBlock(it->first)) {
      out.markers.push_back(
          markerHeader(style, stamp, it->second.id, visualization_msgs::Marker::DELETE));
      it = ledger->ids_.erase(it);
    } else {
      ++it;
    }
  }
  // Occupied markers: only blocks where a cell crossed the occupied threshold; other states:
  // the blocks where a cell's state changed.
  std::vector<fragg::BlockRef> changed = blocks.changedRefsSince(
      since, style.state == fragg::CellState::kOccupied ? fragg::BlockChange::kOccupied
                                                        : fragg::BlockChange::kState);
  // colored_map: blocks whose colours changed are redrawn even with the same cells.
  std::unordered_set<fragg::BlockKey, fragg::BlockKeyHash> recolored;
  if (style.colors) {
    for (const fragg::BlockKey& k : style.colors->recoloredSince(ledger->colors_drawn_))
      if (blocks.findBlock(k)) recolored.insert(k);
    for (const fragg::BlockRef& r : changed) recolored.erase(r.key);
    for (const fragg::BlockKey& k : recolored) changed.push_back({k, blocks.findBlock(k)});
  }
  // The masks in parallel (read-only), the ledger and the messages in order.
  std::vector<CellMask> masks(changed.size());
  const int64_t n = static_cast<int64_t>(changed.size());
#pragma omp parallel for schedule(static) if (n > 256)
  for (int64_t j = 0; j < n; ++j)
    masks[j] = drawnCells(map, blocks, changed[j].key, *changed[j].block, style);
  out.markers.reserve(out.markers.size() + changed.size());
  for (size_t j = 0; j < changed.size(); ++j) {
    const fragg::BlockKey& key = changed[j].key;
    const CellMask& cells = masks[j];
    const auto shown = ledger->ids_.find(key);
    if (shown == ledger->ids_.end()) {
      if (cells.none()) continue;
      const int32_t id = ledger->next_id_++;
      ledger->ids_.emplace(key, MarkerLedger::Shown{id, cells});
      out.markers.push_back(blockMarker(map, key, cells, style, stamp, id));
    } else if (cells.none()) {
      out.markers.push_back(
          markerHeader(style, stamp, shown->second.id, visualization_msgs::Marker::DELETE));
      ledger->ids_.erase(shown);
    } else if (cells != shown->second.cells || recolored.count(key)) {
      shown->second.cells = cells;
      out.markers.push_back(blockMarker(map, key, cells, style, stamp, shown->second.id));
    }
  }
  ledger->published_revision_ = map.revision();
  ledger->view_epoch_ = map.viewEpoch();
  if (style.colors) ledger->colors_drawn_ = style.colors->sequence();
  return out;
}

visualization_msgs::MarkerArray allBlockMarkers(const fragg::Map& map, const MarkerStyle& style,
                                                const ::ros::Time& stamp, MarkerLedger* ledger) {
  visualization_msgs::MarkerArray out;
  out.markers.push_back(markerHeader(style, stamp, 0, visualization_msgs::Marker::DELETEALL));
  ledger->ids_.clear();
  ledger->next_id_ = 0;
  const fragg::BlockView blocks = map.blockView();
  map.forEachBlock([&](const fragg::BlockKey& key, const fragg::Block& block) {
    const CellMask cells = drawnCells(map, blocks, key, block, style);
    if (cells.none()) return;
    const int32_t id = ledger->next_id_++;
    ledger->ids_.emplace(key, MarkerLedger::Shown{id, cells});
    out.markers.push_back(blockMarker(map, key, cells, style, stamp, id));
  });
  ledger->published_revision_ = map.revision();
  ledger->view_epoch_ = map.viewEpoch();
  if (style.colors) ledger->colors_drawn_ = style.colors->sequence();
  return out;
}

visualization_msgs::MarkerArray shownBlockMarkers(const fragg::Map& map, const MarkerStyle& style,
                                                  const ::ros::Time& stamp,
                                                  const MarkerLedger& ledger) {
  visualization_msgs::MarkerArray out;
  out.markers.push_back(markerHeader(style, stamp, 0, visualization_msgs::Marker::DELETEALL));
  const fragg::BlockView blocks = map.blockView();
  for (const auto& [key, shown] : ledger.ids_) {
    // An erased block is still shown until the next increment deletes it: its cells stand
    // nowhere else, so it is left out (that DELETE then finds nothing, which is harmless).
    if (blocks.findBlock(key))
      out.markers.push_back(blockMarker(map, key, shown.cells, style, stamp, shown.id));
  }
  return out;
}

}  // namespace fragg::ros
