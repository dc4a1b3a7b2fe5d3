// fragg::Map -> visualization_msgs/MarkerArray, one CUBE_LIST marker per chunk of blocks
// (MarkerStyle::chunk_blocks blocks a side; 1: one marker per 8x8x8 block), so that a publisher
// sends only the chunks whose drawn cells changed and DELETEs the chunks that no longer hold a
// drawn cell. The drawn cells come from the blocks' state masks (state_masks.h), the blocks to
// look at from Map::changedBlocksSince (kOccupied for occupied markers: only the blocks where a
// cell crossed the occupied threshold; kMasks, the change log, for the others): an update's
// work follows what changed, not the map. Applied in order, the updates show what a
// full rebuild (allBlockMarkers) shows. Paced (pacedBlockMarkersWire): the chunks that changed
// are queued in the ledger and each cloud sends its share of them, every chunk within the pace's
// period of its change, so that a once-a-second update does not come as one burst.
#pragma once

#include <ros/time.h>
#include <visualization_msgs/MarkerArray.h>

#include <bitset>
#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "fragg_map/key.h"
#include "fragg_map/map.h"
#include "fragg_map/ros/cell_colors.h"
#include "fragg_map/ros/height_band.h"
#include "fragg_map/ros/marker_wire.h"
#include "fragg_map/ros/mask_mirror.h"

namespace fragg::ros {

struct MarkerStyle {
  std::string frame_id = "map";
  std::string ns = "occupied";
  fragg::CellState state = fragg::CellState::kOccupied;  ///< the cells drawn
  double color_min_z_m = -1.0;                           ///< bottom of the height colour ramp
  double color_max_z_m = 4.0;                            ///< top of the height colour ramp
  float alpha = 1.0f;
  /// false (octomap_server's height_map false): every cell in `flat_rgb` (alpha above), as
  /// the marker's colour without per-point colours (as octomap_server draws it; 24 bytes a
  /// cell on the wire instead of 40), unless `colors` gives cells their own.
  bool height_colors = true;
  float flat_rgb[3] = {0.0f, 0.0f, 1.0f};
  /// filter_speckles: occupied cells without an occupied neighbour are not drawn (decided when
  /// their block is drawn: a neighbour appearing in another block shows them at their block's
  /// next change or full republish).
  bool hide_speckles = false;
  /// occupancy_min_z / occupancy_max_z: cells whose cube lies outside are not drawn (as
  /// octomap_server draws its occupied and free markers).
  HeightBand heights;
  /// Blocks per side of the chunk one marker draws (>= 1): fewer, larger markers for rviz and
  /// the wire; a change redraws its whole chunk.
  int32_t chunk_blocks = 1;
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

/// Which chunks a marker topic shows, with the marker id each chunk got, the blocks drawn in it
/// and their cells, and the map revision published last. Owned by the publisher; the
/// converters below read and update it.
class MarkerLedger {
 public:
  uint64_t publishedRevision() const { return published_revision_; }
  /// A full set went out (allBlockMarkersWire): the subscribers hold what the ledger records, so
  /// the changes since publishedRevision() can follow as increments, also from an empty map
  /// (revision 0).
  [[nodiscard]] bool started() const { return started_; }
  /// Blocks with drawn cells.
  size_t shownBlocks() const { return shown_blocks_; }
  /// Chunks shown (markers a subscriber holds), and those queued to be sent (paced).
  size_t shownChunks() const { return chunks_.size(); }
  /// Chunks whose change is queued and not yet sent (pacedBlockMarkersWire).
  [[nodiscard]] size_t pendingChunks() const { return pending_.size(); }
  /// The id of the marker that draws block `key`, or -1 when the block is not shown.
  [[nodiscard]] int32_t idOf(const fragg::BlockKey& key) const;
  /// Reads the map through `mirror` from now on (nullptr: through the map's views again): the
  /// increments' take-ins bring it up to date (MaskMirror::sync: the changed blocks' masks,
  /// no write-back of a CUDA map's blocks) and every state is drawn from its masks. The mirror
  /// may be shared with other readers of the same map (the output cache). The full sets
  /// (allBlockMarkersWire, shownBlockMarkersWire) still read the map's view.
  void useMirror(std::shared_ptr<MaskMirror> mirror) { mirror_ = std::move(mirror); }

  /// A block drawn in a chunk, with its drawn cells.
  struct ShownBlock {
    fragg::BlockKey key;
    CellMask cells;
  };
  /// What the ledger keeps of a shown chunk.
  struct Chunk {
    int32_t id = -1;
    std::vector<ShownBlock> blocks;  ///< those with drawn cells
    /// The chunk's marker as last sent, in roscpp's wire layout (its stamp rewritten when
    /// sent): sent again as is in a late subscriber's snapshot; its buffer is written over
    /// when the chunk is drawn again and nothing else holds it.
    std::shared_ptr<WireMarker> wire;
    bool pending = false;  ///< changed since it was last sent (listed in pending_)
    /// Blocks of the chunk listed as changed when the map's changes were taken in, drawn when
    /// the chunk is sent (their cells as they are then): the taking-in lists keys only, so that
    /// its cost does not come on one cloud (pacedBlockMarkersWire).
    std::vector<fragg::BlockKey> listed;
    /// Sent again even if no listed block's drawn cells changed: shown blocks left the map, or
    /// colours changed (colored_map).
    bool redraw = false;
  };

 private:
  friend SerializedMarkerArray pacedBlockMarkersWire(const fragg::Map&, const MarkerStyle&,
                                                     const ::ros::Time&, double, double,
                                                     MarkerLedger*);
  friend SerializedMarkerArray allBlockMarkersWire(const fragg::Map&, const MarkerStyle&,
                                                   const ::ros::Time&, MarkerLedger*);
  friend SerializedMarkerArray shownBlockMarkersWire(const fragg::Map&, const MarkerStyle&,
                                                     const ::ros::Time&, const MarkerLedger&);
  void clear(int32_t chunk_blocks);
  std::unordered_map<fragg::BlockKey, Chunk, fragg::BlockKeyHash> chunks_;  ///< by chunk key
  int32_t chunk_blocks_ = 1;
  size_t shown_blocks_ = 0;
  int32_t next_id_ = 0;
  uint64_t published_revision_ = 0;
  bool started_ = false;                ///< started()
  uint64_t colors_drawn_ = 0;           ///< CellColors::sequence() of the last update (colored_map)
  std::shared_ptr<MaskMirror> mirror_;  ///< useMirror
  /// The updates' serialised arrays are written into these (a full set gets its own buffer).
  std::shared_ptr<WireBufferPool> buffers_ = std::make_shared<WireBufferPool>();
  /// Map::viewEpoch() of the last update: shown blocks can only have left the map (clearBox,
  /// reset, paging) when it moved, so only then are they looked up.
  uint64_t view_epoch_ = 0;
  /// The chunks changed and not yet sent, oldest first, with when they changed (paced).
  struct Pending {
    fragg::BlockKey chunk;
    double since_s = 0.0;
  };
  std::deque<Pending> pending_;
  double last_paced_s_ = 0.0;  ///< now_s of the last paced update (the clouds' interval)
  double last_note_s_ = 0.0;   ///< now_s when the map's changes were last taken in (paced)
  bool paced_ = false;         ///< last_paced_s_ is set
};

/// The chunk (of `chunk_blocks` blocks a side) that holds block `key`.
fragg::BlockKey chunkOf(const fragg::BlockKey& key, int32_t chunk_blocks);

/// Whether `style` draws per-point colours (height colours or a colour table); else the
/// marker's own colour is every cell's.
[[nodiscard]] inline bool perPointColors(const MarkerStyle& style) {
  return style.height_colors || style.colors != nullptr;
}

/// The CUBE_LIST marker of one block: centres of the cells in `cells`, coloured by height (or
/// flat: perPointColors).
visualization_msgs::Marker blockMarker(const fragg::Map& map, const fragg::BlockKey& key,
                                       const CellMask& cells, const MarkerStyle& style,
                                       const ::ros::Time& stamp, int32_t id);

/// Markers for the chunks changed since `ledger->publishedRevision()`: ADD (or modify) for a
/// chunk where a block's drawn cells changed and that still draws some, DELETE for a shown
/// chunk that lost them all. The blocks looked at are those whose drawn state changed (with
/// hidden speckles, their 26 neighbours too), and, when the map's view moved, the shown ones
/// that left the map. Updates the ledger to the map's revision; each redrawn chunk's marker is
/// encoded once in roscpp's wire layout and kept in the ledger (what a publisher sends).
[[nodiscard]] SerializedMarkerArray changedBlockMarkersWire(const fragg::Map& map,
                                                            const MarkerStyle& style,
                                                            const ::ros::Time& stamp,
                                                            MarkerLedger* ledger);

/// changedBlockMarkersWire at a pace, called after every cloud (`now_s`: seconds of a steady or
/// sensor clock): the ledger takes the map's changes in once every `period_s` (the first call,
/// then the first call a period after the last time): the changed blocks are listed by chunk,
/// and the chunks are queued and sent in even shares over the calls of the next period (the
/// interval measured between calls), each chunk's listed blocks drawn when it is sent (their
/// cells as they are then; a chunk whose drawn cells did not change is not sent): each call
/// sends what is left over the calls left, all of it by the time the next changes are taken
/// in. So a changed chunk reaches the subscribers
/// within two periods of its change, in a rolling set spread over the clouds, and a period after
/// the changes stop they see what a full rebuild shows. A late subscriber's snapshot
/// (shownBlockMarkersWire) is the chunks as last sent, to which the queued ones still apply.
/// `period_s` <= 0: the changes taken in and sent at once (changedBlockMarkersWire).
[[nodiscard]] SerializedMarkerArray pacedBlockMarkersWire(const fragg::Map& map,
                                                          const MarkerStyle& style,
                                                          const ::ros::Time& stamp, double now_s,
                                                          double period_s, MarkerLedger* ledger);

/// A full republish (after reset or load, or for a late subscriber): a DELETEALL marker in
/// `style.ns`, then one ADD per chunk with drawn cells. Rebuilds the ledger (and its kept
/// wire).
[[nodiscard]] SerializedMarkerArray allBlockMarkersWire(const fragg::Map& map,
                                                        const MarkerStyle& style,
                                                        const ::ros::Time& stamp,
                                                        MarkerLedger* ledger);

/// What a topic's subscribers see now, for a late subscriber of a latched topic: a DELETEALL,
/// then every chunk the ledger shows, with the ledger's ids and cells (its kept wire, unless
/// the map's view moved or colours are drawn: then drawn again without the blocks that left),
/// so that the topic's next increments apply to it as to everyone else. The ledger is not
/// changed.
[[nodiscard]] SerializedMarkerArray shownBlockMarkersWire(const fragg::Map& map,
                                                          const MarkerStyle& style,
                                                          const ::ros::Time& stamp,
                                                          const MarkerLedger& ledger);

/// changedBlockMarkersWire as the MarkerArray a subscriber receives (tests, tools).
[[nodiscard]] visualization_msgs::MarkerArray changedBlockMarkers(const fragg::Map& map,
                                                                  const MarkerStyle& style,
                                                                  const ::ros::Time& stamp,
                                                                  MarkerLedger* ledger);
/// allBlockMarkersWire as the MarkerArray a subscriber receives.
[[nodiscard]] visualization_msgs::MarkerArray allBlockMarkers(const fragg::Map& map,
                                                              const MarkerStyle& style,
                                                              const ::ros::Time& stamp,
                                                              MarkerLedger* ledger);
/// shownBlockMarkersWire as the MarkerArray a subscriber receives.
[[nodiscard]] visualization_msgs::MarkerArray shownBlockMarkers(const fragg::Map& map,
                                                                const MarkerStyle& style,
                                                                const ::ros::Time& stamp,
                                                                const MarkerLedger& ledger);

}  // namespace fragg::ros
