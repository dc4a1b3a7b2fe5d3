// fragg::Map -> visualization_msgs/MarkerArray, one CUBE_LIST marker per 8x8x8 block, so that
// a publisher can send only the blocks that changed (Map::changedBlocksSince: which cells are
// occupied, for occupied cells; any change otherwise) and DELETE the blocks that no longer
// hold a cell of the drawn state.
#pragma once

#include <ros/time.h>
#include <visualization_msgs/MarkerArray.h>

#include <bitset>
#include <cstdint>
#include <string>
#include <unordered_map>

#include "fragg_map/key.h"
#include "fragg_map/map.h"
#include "fragg_map/ros/cell_colors.h"
#include "fragg_map/ros/height_band.h"

namespace fragg::ros {

struct MarkerStyle {
  std::string frame_id = "map";
  std::string ns = "occupied";
  fragg::CellState state = fragg::CellState::kOccupied;  ///< the cells drawn
  double color_min_z_m = -1.0;                           ///< bottom of the height colour ramp
  double color_max_z_m = 4.0;                            ///< top of the height colour ramp
  float alpha = 1.0f;
  /// false (octomap_server's height_map false): every cell in `flat_rgb` (alpha above).
  bool height_colors = true;
  float flat_rgb[3] = {0.0f, 0.0f, 1.0f};
  /// filter_speckles: occupied cells without an occupied neighbour are not drawn (decided when
  /// their block is drawn: a neighbour appearing in another block shows them at their block's
  /// next change or full republish).
  bool hide_speckles = false;
  /// occupancy_min_z / occupancy_max_z: cells whose cube lies outside are not drawn (as
  /// octomap_server draws its occupied and free markers).
  HeightBand heights;
  /// colored_map: cells with a colour in this table are drawn in it (others as above), and
  /// blocks recoloured since the last update are redrawn. Not owned; nullptr: no colours.
  const CellColors* colors = nullptr;
};

/// Which cells of a block are drawn (bit i: cell index i).
using CellMask = std::bitset<fragg::kCellsPerBlock>;

/// The cells of `block` in `state` (the map's occupancy model).
CellMask cellMask(const fragg::Map& map, const fragg::Block& block, fragg::CellState state);

/// The cells of block `key` that `style` draws: in its state, inside its heights, speckles
/// left out when it hides them.
CellMask drawnCells(const fragg::Map& map, const fragg::BlockView& blocks,
                    const fragg::BlockKey& key, const fragg::Block& block,
                    const MarkerStyle& style);

/// Which blocks a marker topic shows, with the marker id each block got and the cells drawn,
/// and the map revision published last. Owned by the publisher; the converters below read and
/// update it.
class MarkerLedger {
 public:
  uint64_t publishedRevision() const { return published_revision_; }
  size_t shownBlocks() const { return ids_.size(); }
  /// The id of `key`'s marker, or -1 when the block is not shown.
  int32_t idOf(const fragg::BlockKey& key) const;

 private:
  friend visualization_msgs::MarkerArray changedBlockMarkers(const fragg::Map&, const MarkerStyle&,
                                                             const ::ros::Time&, MarkerLedger*);
  friend visualization_msgs::MarkerArray allBlockMarkers(const fragg::Map&, const MarkerStyle&,
                                                         const ::ros::Time&, MarkerLedger*);
  friend visualization_msgs::MarkerArray shownBlockMarkers(const fragg::Map&, const MarkerStyle&,
                                                           const ::ros::Time&, const MarkerLedger&);
  struct Shown {
    int32_t id;
    CellMask cells;
  };
  std::unordered_map<fragg::BlockKey, Shown, fragg::BlockKeyHash> ids_;
  int32_t next_id_ = 0;
  uint64_t published_revision_ = 0;
  uint64_t colors_drawn_ = 0;  ///< CellColors::sequence() of the last update (colored_map)
  /// Map::viewEpoch() of the last update: shown blocks can only have left the map (clearBox,
  /// reset, paging) when it moved, so only then are they looked up.
  uint64_t view_epoch_ = 0;
};

/// The CUBE_LIST marker of one block: centres of the cells in `cells`, coloured by height.
visualization_msgs::Marker blockMarker(const fragg::Map& map, const fragg::BlockKey& key,
                                       const CellMask& cells, const MarkerStyle& style,
                                       const ::ros::Time& stamp, int32_t id);

/// Markers for the blocks changed since `ledger->publishedRevision()`: ADD (or modify) for a
/// changed block whose set of cells in `style.state` changed and is not empty, DELETE for a
/// shown block that lost them all or no longer exists. A block whose drawn cells stayed the
/// same (e.g. only its free cells changed) is not sent. Updates the ledger to the map's
/// revision.
visualization_msgs::MarkerArray changedBlockMarkers(const fragg::Map& map, const MarkerStyle& style,
                                                    const ::ros::Time& stamp, MarkerLedger* ledger);

/// A full republish (after reset or load, or for a late subscriber): a DELETEALL marker in
/// `style.ns`, then one ADD per block with cells in `style.state`. Rebuilds the ledger.
visualization_msgs::MarkerArray allBlockMarkers(const fragg::Map& map, const MarkerStyle& style,
                                                const ::ros::Time& stamp, MarkerLedger* ledger);

/// What a topic's subscribers see now, for a late subscriber of a latched topic: a DELETEALL,
/// then every block the ledger shows, with the ledger's ids and cells, so that the topic's
/// next increments apply to it as to everyone else. The ledger is not changed.
visualization_msgs::MarkerArray shownBlockMarkers(const fragg::Map& map, const MarkerStyle& style,
                                                  const ::ros::Time& stamp,
                                                  const MarkerLedger& ledger);

}  // namespace fragg::ros
