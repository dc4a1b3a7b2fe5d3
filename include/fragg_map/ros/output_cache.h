// The map server's whole-map outputs kept incrementally: per-block pieces of the occupied
// cloud (packed cell centres) and of the projected map (the block's 8 x 8 columns in the
// height band), refreshed only for the blocks where a cell's state changed since the last
// update (Map::changedBlocksSince with BlockChange::kState: free cells getting freer leave a
// block alone; with the 26 neighbours of each when speckles are hidden), and
// rebuilt from scratch when the map's view changed otherwise (Map::viewEpoch: erase,
// clear_bbx, truncate, reset, load, paging) or the revision went back. The projected grid
// itself is kept between updates and patched in the changed columns (octomap_server's
// incremental_2D_projection); messages are assembled from the pieces (a copy of the output,
// no pass over the cells). The results equal occupiedCloud() and projectedMap() of the same
// map as sets (point order differs). Paced (advance()): the changed blocks are listed at a
// publication and recomputed in even shares over the clouds of the next period, so that the
// work follows the clouds instead of coming as one backlog per publication; a block's change
// reaches the outputs within two periods (listed within one, recomputed within the next), and
// update() catches up at once. The occupied cloud is also kept as the next publication's
// message in roscpp's wire layout (occupiedCloudWire): paced, once a period's queue is
// recomputed (by kRecomputedBy of the period), the following clouds gather the pieces into it in
// shares, so that a publication neither gathers nor serialises the whole cloud. Not
// thread-safe: one owner, under the map's read lock.
#pragma once

#include <nav_msgs/OccupancyGrid.h>
#include <ros/time.h>
#include <sensor_msgs/PointCloud2.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <deque>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "fragg_map/block_key_table.h"
#include "fragg_map/key.h"
#include "fragg_map/map.h"
#include "fragg_map/ros/height_band.h"
#include "fragg_map/ros/mask_mirror.h"
#include "fragg_map/ros/wire_payload.h"
#include "fragg_map/state_masks.h"

namespace fragg::ros {

struct OutputCacheOptions {
  /// occupancy_min_z / occupancy_max_z: cells whose cube lies outside the band are left out
  /// of both the occupied cloud and the projected map (height_band.h, as octomap_server).
  double occupancy_min_z_m = -std::numeric_limits<double>::infinity();
  double occupancy_max_z_m = std::numeric_limits<double>::infinity();
  /// filter_speckles: occupied cells without an occupied neighbour are left out of both.
  bool hide_speckles = false;
  /// The projected map spans octomap_server's grid (octomapServerGridSpan of the observed
  /// cells' bounds) instead of those bounds.
  bool octomap_bounds = false;
  /// Which blocks an update recomputes: those whose state masks changed (kMasks: from the
  /// map's change log, no walk over the blocks, while the last update is at most two revisions
  /// behind; further behind, on the CPU backend, from a walk over the blocks' kState stamps,
  /// cheaper than de-duplicating many revisions' records), those where a cell's state changed
  /// (kState, found by a walk over the blocks' stamps), or every changed block (kAny: the behaviour
  /// before BlockMeta::state_at, kept for same-run comparisons in fragg_map_server_overhead).
  /// kMasks falls back to kState for a model where a cell's first update can leave it in the
  /// unknown band (observed without a mask change: the projected map's bounds would miss it).
  /// kOccupied would miss free cells: refused.
  fragg::BlockChange refresh_on = fragg::BlockChange::kMasks;
  /// With kMasks in effect, a block whose cells cannot widen the projected map's bounds is
  /// recomputed from its state masks alone; false: every block from its cells (the behaviour
  /// before, kept for same-run comparisons in fragg_map_server_overhead --cells-always).
  bool masks_where_settled = true;
};

/// What an update did.
struct OutputCacheUpdate {
  bool full = false;          ///< rebuilt from every block
  size_t blocks_read = 0;     ///< blocks whose pieces were recomputed
  size_t columns_merged = 0;  ///< 8 x 8 column groups of the grid recomputed
  /// Of blocks_read, those whose cells were read (the others from their state masks alone).
  size_t blocks_cells_read = 0;
  /// advance(): blocks left queued for later clouds (0 after update()).
  size_t blocks_queued = 0;
  /// advance(): pieces gathered into the next publication's occupied cloud, and their bytes.
  size_t pieces_gathered = 0, bytes_gathered = 0;
  /// Wall milliseconds of its stages: the blocks to refresh listed (change log, look-ups), the
  /// pieces found or made and recomputed, the columns merged and the grid drawn, the pieces
  /// gathered into the next occupied cloud message.
  double list_ms = 0.0, pieces_ms = 0.0, grid_ms = 0.0, gather_ms = 0.0;
  /// Wall milliseconds of pieces_ms's parts: pieces found or made (in order), recomputed (in
  /// parallel), their changes summed into the columns (in order).
  double pieces_made_ms = 0.0, pieces_computed_ms = 0.0, pieces_summed_ms = 0.0;
};

class MapOutputCache {
 public:
  /// Throws fragg::InvalidArgument for NaN heights or min > max (as projectedMap).
  explicit MapOutputCache(const OutputCacheOptions& options = OutputCacheOptions());

  /// Brings the pieces and the grid up to date with `map` (held under its read lock), the
  /// blocks advance() left queued included.
  OutputCacheUpdate update(const fragg::Map& map);
  /// One cloud's share of a paced refresh (`map` under its read lock). `with_grid` (a
  /// publication follows: the grid is drawn): what is left of the last list is recomputed and
  /// the blocks changed since are listed and queued (stamped `now_s`); otherwise this cloud's
  /// share of the queue is recomputed, what is left over the clouds left until the list is
  /// `period_s` old (the clouds' interval measured between calls), so the queue is empty by
  /// the next publication. The columns are merged either way, the grid's bounds kept current.
  /// `period_s` <= 0: as update(). A rebuild (view moved, first call) is done whole at once.
  /// The queue is recomputed by kRecomputedBy of the period; the clouds after it gather the
  /// pieces into the next occupied cloud message in shares (what is left over the clouds left
  /// until the next publication), unless `gather_cloud` is false (nobody wants the cloud).
  OutputCacheUpdate advance(const fragg::Map& map, double now_s, double period_s, bool with_grid,
                            bool gather_cloud = true);
  /// Part of a period by which advance() recomputes what a publication listed; the rest of the
  /// period gathers the occupied cloud.
  static constexpr double kRecomputedBy = 0.8;
  /// Forgets everything: the next update rebuilds.
  void invalidate() { valid_ = false; }
  /// Reads the map through `mirror` from now on (nullptr: through the map's views again; the
  /// next update rebuilds either way): listings bring it up to date (MaskMirror::sync: the
  /// changed blocks' masks, no write-back of a CUDA map's blocks), shares read it as it stands,
  /// and cells (only where the grid's bounds need them) come from Map::hostBlockView(). Used
  /// where the map's refresh_on is kMasks with masks_where_settled (else the map's views serve).
  /// The mirror may be shared with other readers of the same map (the markers' ledger).
  void useMirror(std::shared_ptr<MaskMirror> mirror) {
    mirror_ = std::move(mirror);
    valid_ = false;
  }
  /// Blocks queued by advance() and not yet recomputed.
  [[nodiscard]] size_t queuedBlocks() const { return queue_.size() - queue_head_; }

  /// The occupied cloud of the last update: packed float32 x, y, z (as occupiedCloud()),
  /// gathered from the pieces that hold cells into a message kept by the cache (valid until
  /// the next call): its buffer is reused, so a publication writes into pages it already has.
  const sensor_msgs::PointCloud2& occupiedCloud(const std::string& frame_id,
                                                const ::ros::Time& stamp) const;
  /// The projected map of the last update (as projectedMap()).
  nav_msgs::OccupancyGrid projectedMap(const std::string& frame_id, const ::ros::Time& stamp) const;
  /// occupiedCloud() as roscpp serialises it (what a publisher sends: serializeMessage hands
  /// these bytes on), from the pieces gathered by advance() and what is left gathered now
  /// (all of it after update()). The message owns its buffer; the cache gathers the next one
  /// into another.
  [[nodiscard]] PreserializedCloud occupiedCloudWire(const std::string& frame_id,
                                                     const ::ros::Time& stamp);
  /// projectedMap() as roscpp serialises it: the grid copied once into a kept buffer.
  [[nodiscard]] PreserializedGrid projectedMapWire(const std::string& frame_id,
                                                   const ::ros::Time& stamp);
  size_t occupiedCells() const { return occupied_cells_; }
  uint64_t revision() const { return revision_; }

 private:
  /// projectedMap()'s header and info (size and origin from the last update), no cells.
  nav_msgs::OccupancyGrid gridWithoutData(const std::string& frame_id,
                                          const ::ros::Time& stamp) const;
  /// The change kind to list for `model` (options_.refresh_on, kMasks checked).
  fragg::BlockChange refreshOn(const fragg::OccupancyModel& model) const;
  HeightBand heights() const { return {options_.occupancy_min_z_m, options_.occupancy_max_z_m}; }

  static constexpr uint32_t kNoColumn = UINT32_MAX;  ///< Piece::column of an unused slot
  /// A block's outputs. Pieces live in one deque indexed by the block's slot in the map
  /// (BlockView::slotCount; never moved as it grows): the tens of thousands of blocks a LiDAR
  /// second lists are read and written in storage order, with no look-up per block. A piece
  /// keeps its block's key: a slot another block took over is dropped and made again.
  struct Piece {
    fragg::BlockKey key;
    /// The occupied cells shown (in the band, speckles left out when hidden), one word per z
    /// layer: the occupied cloud's points, their centres written where it is gathered (no
    /// per-block list of centres kept).
    std::array<uint64_t, fragg::kBlockSize> shown{};
    /// The block's columns in the height band (bit lx + 8 ly): some cell occupied, some free.
    uint64_t band_occupied = 0, band_free = 0;
    /// Observed cells' xy key bounds within the block (lo > hi: none observed).
    int8_t min_x = 0, max_x = -1, min_y = 0, max_y = -1;
    uint32_t column = kNoColumn;  ///< its place in columns_; kNoColumn: no piece here
    int64_t listed = -1;          ///< its place in with_cells_; -1 while none is shown
    uint32_t shown_cells = 0;     ///< cells set in `shown`
  };
  /// What recomputing a piece changed.
  struct PieceDelta {
    int64_t occupied = 0;     ///< shown occupied cells gained (negative: lost)
    bool column = false;      ///< its columns or bounds changed: its column takes the change
    bool cells_read = false;  ///< the block's cells were read (not its masks alone)
    /// With `column`: its columns before (what its column's counts held of it).
    uint64_t occupied_before = 0, free_before = 0;
    bool bounds_shrank = false;  ///< with `column`: it lost bounds (the grid's may shrink)
  };
  /// A block to recompute: its slot and key, its state masks (nullptr: read the cells).
  struct Source {
    fragg::BlockIndex slot = fragg::kNoBlock;
    fragg::BlockKey key;
    const fragg::BlockStateMasks* masks = nullptr;
  };
  /// A block listed for a later cloud (advance()): the slot checked against the key then.
  struct Queued {
    fragg::BlockIndex slot;
    fragg::BlockKey key;
  };
  /// A column of blocks (same x, y block key): its pieces, the merged 8 x 8 grid patch (bit
  /// lx + 8 ly: occupied in some block, else free in some block), kept by counting the pieces
  /// occupied and free at each bit (a piece's change moves the counts: no pass over the
  /// column's pieces), and the xy bounds. Columns stay in columns_ once made (an emptied one
  /// shows unknown and no bounds) until a rebuild.
  struct Column {
    int32_t x = 0, y = 0;
    std::vector<uint32_t> pieces;  ///< indices into pieces_
    uint64_t occupied = 0, free = 0;
    std::array<uint16_t, 64> n_occupied{}, n_free{};  ///< pieces occupied / free at each bit
    int8_t min_x = 0, max_x = -1, min_y = 0, max_y = -1;
    bool dirty = false;    ///< listed in the update's dirty columns (bounds merged again)
    bool undrawn = false;  ///< merged since the grid was last drawn (listed in undrawn_)
  };
  // `View`: fragg::BlockView (the map's view: slots are the map's) or MaskMirror (slots are
  // the mirror's; `cells` the host's blocks, where the grid's bounds need cells).
  /// The blocks changed since the last update (all of them for a rebuild, `full`), in slot
  /// order. `keys_only`: the sources' masks are left out (they are queued).
  template <class View>
  void listChanges(const fragg::Map& map, const View& blocks, bool full, bool masks_suffice,
                   bool keys_only, std::vector<Source>* out);
  /// Recomputes the pieces of `sources` (distinct blocks of the map), adding to `out`.
  template <class View>
  void recompute(const fragg::Map& map, const View& blocks, const fragg::BlockView& cells,
                 const std::vector<Source>& sources, bool masks_suffice, OutputCacheUpdate* out);
  /// The common path of update() and advance(): `period_s` <= 0 recomputes everything listed
  /// and queued.
  OutputCacheUpdate refresh(const fragg::Map& map, double now_s, double period_s, bool with_grid,
                            bool gather_cloud);
  /// refresh() over the chosen view, once it has decided whether to rebuild (`update->full`),
  /// whether it is paced and whether it lists.
  template <class View>
  void refreshOver(const fragg::Map& map, const View& blocks, const fragg::BlockView& cells,
                   double now_s, double period_s, bool paced, bool list, bool with_grid,
                   bool gather_cloud, bool masks_suffice, std::chrono::steady_clock::time_point t0,
                   OutputCacheUpdate* update);

  /// Brings `piece` (new: default-constructed) up to date with `source`'s block. With
  /// `masks_suffice` (the change log lists every block where a cell became observed: refreshOn
  /// is kMasks) and source.masks, the masks alone serve where boundsSettled.
  template <class View>
  PieceDelta computePiece(const fragg::Map& map, const View& blocks, const fragg::BlockView& cells,
                          const Source& source, bool masks_suffice, Piece* piece) const;
  /// Observed xy key bounds within a block (min > max: none).
  struct XyBounds {
    int32_t min_x = fragg::kBlockSize, max_x = -1, min_y = fragg::kBlockSize, max_y = -1;
  };
  /// The first and last x and y of the columns set in `columns_xy` (bit lx + 8 ly).
  static XyBounds xyBoundsOf(uint64_t columns_xy);
  /// Whether no cell of the block can widen the projected map's bounds beyond `known` (the
  /// observed bounds its masks and kept bounds show), side by side: on each side either the
  /// block lies inside the map's observed bounds, or `known` reaches the block's edge (cells
  /// the masks miss, observed in the unknown band, lie inside the block).
  bool boundsSettled(const fragg::BlockKey& key, const XyBounds& known) const;
  /// Makes the piece of `source`'s block (registered in its column, empty) when it has none;
  /// a piece of another block in the slot is dropped first. The piece's index is the slot.
  void pieceFor(const Source& source);
  /// Lists `piece` in with_cells_ when it holds cells, takes it out when it does not.
  void relist(uint32_t piece);
  void unlist(uint32_t piece);
  /// Marks column `c` dirty (once per update).
  void markDirty(uint32_t c);
  /// Drops the piece in `slot` (if any): its block left the map or the slot went to another
  /// block; its column becomes dirty.
  void dropPiece(uint32_t slot);
  /// Recomputes `col`'s bounds from its blocks' pieces.
  void mergeBounds(Column* col) const;
  /// Moves `col`'s counts and patch from a piece's columns before to after.
  static void countPiece(Column* col, uint64_t occupied_before, uint64_t free_before,
                         uint64_t occupied_after, uint64_t free_after);
  /// Widens `col`'s bounds by `piece`'s.
  static void widenColumn(Column* col, const Piece& piece);
  /// Widens the observed cells' bounds (seen_*) by `col`'s.
  void widenSeen(const Column& col);
  /// Lists column `c` in undrawn_ (once).
  void markUndrawn(uint32_t c);
  /// Grid bounds from the columns (kept for boundsSettled); draws the columns merged since the
  /// last draw into the tiles (every call: the tiles do not move with the bounds); with `draw`
  /// (a publication), also a whole redraw when one is owed (`all`: a rebuild) and the published
  /// rectangle; without, a whole redraw waits for the next call with `draw`.
  void refreshGrid(bool all, bool draw);
  void drawColumn(const Column& col);
  /// Gathers the next `pieces` of with_cells_ into the next cloud message (gathered_ on).
  void gatherCloud(size_t pieces);
  /// Writes the centres of `piece`'s shown cells at `dst` (packed float32 x, y, z, as
  /// Map::centerOf); returns the end.
  uint8_t* writeCenters(const Piece& piece, uint8_t* dst) const;
  /// The pieces changed: the next cloud message is gathered from the start.
  void regather() { gathered_ = 0, gathered_bytes_ = 0; }

  OutputCacheOptions options_;
  std::shared_ptr<MaskMirror> mirror_;  ///< useMirror
  uint64_t mirror_generation_ = 0;      ///< the mirror's generation the pieces' slots are of
  bool valid_ = false;
  uint64_t revision_ = 0;
  uint64_t epoch_ = 0;
  double resolution_m_ = 0.0;
  std::deque<Piece> pieces_;  ///< by the blocks' slots (BlockView::slotCount)
  /// The pieces with occupied cells shown (a small part of pieces_: most blocks hold free
  /// space only), so that the cloud is gathered without walking the others.
  std::vector<uint32_t> with_cells_;
  mutable sensor_msgs::PointCloud2 cloud_msg_;  ///< occupiedCloud()'s message and buffer
  std::vector<Column> columns_;
  fragg::BlockKeyTable column_index_;  ///< {x, y, 0} block key -> index into columns_
  std::vector<uint32_t> dirty_;        ///< columns whose bounds are merged in this update
  std::vector<uint32_t> undrawn_;      ///< columns merged since the grid was last drawn
  std::vector<uint32_t> drawing_;      ///< refreshGrid's copy of undrawn_ (kept for its memory)
  bool redraw_owed_ = false;           ///< a rebuild since the grid was last drawn
  // Scratch kept between updates (their pages stay resident: fresh memory faults in at each
  // first write, ~3.7 ms per 2 MiB huge page on the 2-core VM).
  std::vector<Source> sources_;           ///< the blocks an update recomputes
  std::vector<fragg::BlockIndex> slots_;  ///< listChanges' slots
  std::vector<PieceDelta> deltas_;        ///< recompute's per-block results
  /// advance(): the blocks of the last list not recomputed yet, from queue_head_ on.
  std::vector<Queued> queue_;
  size_t queue_head_ = 0;
  double queued_since_s_ = 0.0;  ///< now_s when queue_ was listed
  double last_advance_s_ = 0.0;  ///< now_s of the last advance() (the clouds' interval)
  bool advanced_ = false;        ///< last_advance_s_ is set
  size_t occupied_cells_ = 0;
  /// The observed cells' xy key bounds at the last update (seen_valid_: some cell observed).
  bool seen_valid_ = false;
  /// A piece left or lost bounds: seen_* are recomputed over every column.
  bool bounds_stale_ = false;
  int64_t seen_lo_x_ = 0, seen_hi_x_ = -1, seen_lo_y_ = 0, seen_hi_y_ = -1;
  // The grid published: cells [grid_min_x, +width) x [grid_min_y, +height) (the observed
  // bounds, or octomap_server's span of them).
  bool grid_empty_ = true;
  int32_t grid_min_x_ = 0, grid_min_y_ = 0;
  int64_t grid_width_ = 0, grid_height_ = 0;
  /// The grid's cells, drawn column by column into tiles of kTileCells x kTileCells (made
  /// where a column is first drawn, unknown until then): the published rectangle moves as the
  /// map grows (at nearly every publication while the sensor moves) without a redraw or a new
  /// buffer; a publication copies the rectangle out of the tiles (copyPublished).
  static constexpr int kTileBits = 8;
  static constexpr int64_t kTileCells = int64_t{1} << kTileBits;
  struct Tile {
    std::array<int8_t, kTileCells * kTileCells> cells;  ///< row-major (y rows)
  };
  std::deque<Tile> tiles_;           ///< never moved as it grows
  fragg::BlockKeyTable tile_index_;  ///< {tile x, tile y, 0} -> index into tiles_
  /// The tile holding cell (x, y) (made, unknown, when missing).
  Tile& tileAt(int64_t x, int64_t y);
  /// Copies the published rectangle to `dst` (grid_width_ * grid_height_ bytes, row-major).
  void copyPublished(int8_t* dst) const;
  /// The next occupied cloud message's payload: with_cells_[0, gathered_) are in it, their
  /// gathered_bytes_ written (the pieces have not changed since: any recompute starts over).
  WirePayload cloud_wire_;
  size_t gathered_ = 0, gathered_bytes_ = 0;
  WirePayload grid_wire_;
};

}  // namespace fragg::ros
