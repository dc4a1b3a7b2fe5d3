// Whole-map outputs (occupied cloud, projected map) kept per block, refreshed for the changed
// blocks only.
#include "fragg_map/ros/output_cache.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "fragg_map/errors.h"
#include "fragg_map/ros/layer_masks.h"
#include "fragg_map/ros/occupied_cloud.h"
#include "fragg_map/ros/projected_map.h"
#include "fragg_map/ros/speckles.h"

namespace fragg::ros {
namespace {

/// Revisions since the last update up to which the change log lists the blocks to refresh;
/// beyond, the blocks' stamps are walked (MapOutputCache::update).
constexpr uint64_t kLogRevisions = 2;

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

}  // namespace

using grid_value::kFree;
using grid_value::kOccupied;
using grid_value::kUnknown;

MapOutputCache::MapOutputCache(const OutputCacheOptions& options) : options_(options) {
  heights().validate();
  if (options_.refresh_on == fragg::BlockChange::kOccupied)
    throw fragg::InvalidArgument("output cache: refresh_on kOccupied would miss free cells");
}

MapOutputCache::XyBounds MapOutputCache::xyBoundsOf(uint64_t columns_xy) {
  XyBounds b;
  if (!columns_xy) return b;
  uint64_t rows = 0, xs = 0;
  for (int ly = 0; ly < fragg::kBlockSize; ++ly) {
    const uint64_t row = columns_xy >> (fragg::kBlockSize * ly) & 0xff;
    rows |= uint64_t{row != 0} << ly;
    xs |= row;
  }
  b.min_x = __builtin_ctzll(xs), b.max_x = 63 - __builtin_clzll(xs);
  b.min_y = __builtin_ctzll(rows), b.max_y = 63 - __builtin_clzll(rows);
  return b;
}

bool MapOutputCache::boundsSettled(const fragg::BlockKey& key, const XyBounds& known) const {
  // Cells `known` misses (observed, in the unknown band) lie inside the block: on a side where
  // `known` reaches the block's edge, or where the block lies inside the map's observed bounds,
  // none of them can widen the bounds.
  const int64_t x0 = int64_t{key.x} * fragg::kBlockSize, y0 = int64_t{key.y} * fragg::kBlockSize;
  const int64_t x1 = x0 + fragg::kBlockMask, y1 = y0 + fragg::kBlockMask;
  return (known.min_x == 0 || (seen_valid_ && x0 >= seen_lo_x_)) &&
         (known.max_x == fragg::kBlockMask || (seen_valid_ && x1 <= seen_hi_x_)) &&
         (known.min_y == 0 || (seen_valid_ && y0 >= seen_lo_y_)) &&
         (known.max_y == fragg::kBlockMask || (seen_valid_ && y1 <= seen_hi_y_));
}

template <class View>
MapOutputCache::PieceDelta MapOutputCache::computePiece(const fragg::Map& map, const View& blocks,
                                                        const fragg::BlockView& cells,
                                                        const Source& source, bool masks_suffice,
                                                        Piece* piece) const {
  // One 64-bit word per z layer of the block (cell index x + 8 y + 64 z): occupied and free
  // from the block's state masks (no cell read) where the observed bounds need no cells
  // (boundsSettled), else occupied, free and observed from the cells (layer_masks.h); the
  // columns and bounds from OR-ed layers; the cell centres only when the shown occupied cells
  // changed (most state changes are cells seen for the first time or turning free).
  const fragg::BlockKey& key = source.key;
  PieceDelta delta;
  // From the masks: the observed columns they show (free or occupied cells) widened by the
  // kept bounds (exact when last read from the cells; observed cells stay observed until a
  // rebuild): the masks miss observed cells in the unknown band.
  const bool masks_may_serve = source.masks && masks_suffice;
  XyBounds masks_bounds;
  if (masks_may_serve) {
    uint64_t masks_xy = 0;
    for (int z = 0; z < fragg::kBlockSize; ++z)
      masks_xy |= source.masks->occupied[z] | source.masks->free[z];
    masks_bounds = xyBoundsOf(masks_xy);
    if (piece->max_x >= 0) {
      masks_bounds.min_x = std::min<int32_t>(masks_bounds.min_x, piece->min_x);
      masks_bounds.max_x = std::max<int32_t>(masks_bounds.max_x, piece->max_x);
      masks_bounds.min_y = std::min<int32_t>(masks_bounds.min_y, piece->min_y);
      masks_bounds.max_y = std::max<int32_t>(masks_bounds.max_y, piece->max_y);
    }
  }
  bool from_masks = masks_may_serve && boundsSettled(key, masks_bounds);
  const fragg::Block* block = nullptr;
  if (!from_masks) {
    if constexpr (std::is_same_v<View, fragg::BlockView>) {
      block = &blocks.blockAt(source.slot);
    } else {
      // A mirror holds masks only: the cells as the host holds them (a CUDA map's block may be
      // older there, or missing: then its masks and kept bounds serve).
      block = cells.findBlock(key);
      from_masks = block == nullptr;
    }
  }
  delta.cells_read = !from_masks;
  const fragg::OccupancyModel& model = map.model();
  const int16_t above = model.occupied_above_fx, below = model.free_below_fx;
  const uint8_t shown_layers = heights().blockLayers(key.z, map.resolution());
  std::array<uint64_t, fragg::kBlockSize> shown{};
  uint64_t observed_xy = 0, band_occupied = 0, band_free = 0;
  for (int z = 0; z < fragg::kBlockSize; ++z) {
    uint64_t o, f;
    if (from_masks) {
      o = source.masks->occupied[z];
      f = source.masks->free[z];
    } else {
      const LayerMasks layer = layerMasks(block->cells + 64 * z, above, below);
      o = layer.occupied;
      f = layer.free;
      observed_xy |= layer.observed;
    }
    if (!(shown_layers >> z & 1)) continue;  // outside occupancy_min_z / max_z: not shown
    if (options_.hide_speckles) {
      for (uint64_t m = o; m; m &= m - 1) {
        const int i = __builtin_ctzll(m);
        if (isSpeckle(map, blocks, fragg::voxelKeyOf(key, 64 * z + i))) o &= ~(uint64_t{1} << i);
      }
    }
    shown[z] = o;
    band_occupied |= o;  // a speckle counts neither as occupied nor as free
    band_free |= f;
  }
  if (shown != piece->shown) {
    const int64_t before = piece->shown_cells;
    piece->shown = shown;
    uint32_t cells = 0;
    for (const uint64_t word : shown) cells += static_cast<uint32_t>(__builtin_popcountll(word));
    piece->shown_cells = cells;
    delta.occupied = static_cast<int64_t>(cells) - before;
  }
  // A column is occupied where a cell of it is, else free where one is (the grid's values).
  band_free &= ~band_occupied;
  const XyBounds bounds = from_masks ? masks_bounds : xyBoundsOf(observed_xy);
  const int32_t min_x = bounds.min_x, max_x = bounds.max_x;
  const int32_t min_y = bounds.min_y, max_y = bounds.max_y;
  if (band_occupied != piece->band_occupied || band_free != piece->band_free ||
      min_x != piece->min_x || max_x != piece->max_x || min_y != piece->min_y ||
      max_y != piece->max_y) {
    // What its column's counts held of it, and whether it lost bounds.
    // Bounds shrink only where observed cells became unobserved (a scan removed).
    delta.bounds_shrank =
        piece->max_x >= 0 && (max_x < 0 || min_x > piece->min_x || max_x < piece->max_x ||
                              min_y > piece->min_y || max_y < piece->max_y);
    delta.occupied_before = piece->band_occupied;
    delta.free_before = piece->band_free;
    piece->band_occupied = band_occupied;
    piece->band_free = band_free;
    piece->min_x = static_cast<int8_t>(min_x), piece->max_x = static_cast<int8_t>(max_x);
    piece->min_y = static_cast<int8_t>(min_y), piece->max_y = static_cast<int8_t>(max_y);
    delta.column = true;
  }
  return delta;
}

void MapOutputCache::countPiece(Column* col, uint64_t occupied_before, uint64_t free_before,
                                uint64_t occupied_after, uint64_t free_after) {
  const uint64_t occupied_moved = occupied_before ^ occupied_after;
  const uint64_t free_moved = free_before ^ free_after;
  for (uint64_t m = occupied_moved; m; m &= m - 1) {
    const int b = __builtin_ctzll(m);
    col->n_occupied[b] =
        static_cast<uint16_t>(col->n_occupied[b] + (occupied_after >> b & 1 ? 1 : -1));
  }
  for (uint64_t m = free_moved; m; m &= m - 1) {
    const int b = __builtin_ctzll(m);
    col->n_free[b] = static_cast<uint16_t>(col->n_free[b] + (free_after >> b & 1 ? 1 : -1));
  }
  // The patch where a count moved: occupied where some piece is, else free where some piece is.
  for (uint64_t m = occupied_moved | free_moved; m; m &= m - 1) {
    const int b = __builtin_ctzll(m);
    const uint64_t bit = uint64_t{1} << b;
    const bool occupied = col->n_occupied[b] > 0;
    col->occupied = occupied ? col->occupied | bit : col->occupied & ~bit;
    col->free = !occupied && col->n_free[b] > 0 ? col->free | bit : col->free & ~bit;
  }
}

void MapOutputCache::widenColumn(Column* col, const Piece& piece) {
  if (piece.max_x < 0) return;
  if (col->max_x < 0) {
    col->min_x = piece.min_x, col->max_x = piece.max_x;
    col->min_y = piece.min_y, col->max_y = piece.max_y;
    return;
  }
  col->min_x = std::min(col->min_x, piece.min_x);
  col->max_x = std::max(col->max_x, piece.max_x);
  col->min_y = std::min(col->min_y, piece.min_y);
  col->max_y = std::max(col->max_y, piece.max_y);
}

void MapOutputCache::widenSeen(const Column& col) {
  if (col.max_x < 0) return;
  const int64_t x0 = int64_t{col.x} * fragg::kBlockSize, y0 = int64_t{col.y} * fragg::kBlockSize;
  const int64_t lo_x = x0 + col.min_x, hi_x = x0 + col.max_x;
  const int64_t lo_y = y0 + col.min_y, hi_y = y0 + col.max_y;
  if (!seen_valid_) {
    seen_valid_ = true;
    seen_lo_x_ = lo_x, seen_hi_x_ = hi_x, seen_lo_y_ = lo_y, seen_hi_y_ = hi_y;
    return;
  }
  seen_lo_x_ = std::min(seen_lo_x_, lo_x);
  seen_hi_x_ = std::max(seen_hi_x_, hi_x);
  seen_lo_y_ = std::min(seen_lo_y_, lo_y);
  seen_hi_y_ = std::max(seen_hi_y_, hi_y);
}

void MapOutputCache::markUndrawn(uint32_t c) {
  Column& col = columns_[c];
  if (col.undrawn) return;
  col.undrawn = true;
  undrawn_.push_back(c);
}

void MapOutputCache::mergeBounds(Column* col) const {
  col->min_x = col->min_y = fragg::kBlockSize;
  col->max_x = col->max_y = -1;
  for (const uint32_t i : col->pieces) widenColumn(col, pieces_[i]);
}

void MapOutputCache::relist(uint32_t i) {
  Piece& piece = pieces_[i];
  const bool has_cells = piece.shown_cells > 0;
  if (has_cells == (piece.listed >= 0)) return;
  if (!has_cells) return unlist(i);
  piece.listed = static_cast<int64_t>(with_cells_.size());
  with_cells_.push_back(i);
}

void MapOutputCache::unlist(uint32_t i) {
  Piece& piece = pieces_[i];
  if (piece.listed < 0) return;
  const uint32_t last = with_cells_.back();
  with_cells_[static_cast<size_t>(piece.listed)] = last;
  pieces_[last].listed = piece.listed;
  with_cells_.pop_back();
  piece.listed = -1;
}

void MapOutputCache::markDirty(uint32_t c) {
  if (columns_[c].dirty) return;
  columns_[c].dirty = true;
  dirty_.push_back(c);
}

void MapOutputCache::pieceFor(const Source& source) {
  const uint32_t i = source.slot;
  const fragg::BlockKey& key = source.key;
  if (i >= pieces_.size()) pieces_.resize(i + 1);
  if (pieces_[i].column != kNoColumn) {
    if (pieces_[i].key == key) return;
    dropPiece(i);  // the slot's block left the map (paged out) and another took the slot
  }
  const fragg::BlockKey column_key{key.x, key.y, 0};
  uint32_t c = column_index_.find(column_key);
  if (c == fragg::BlockKeyTable::kNone) {
    c = static_cast<uint32_t>(columns_.size());
    columns_.emplace_back();
    columns_.back().x = key.x;
    columns_.back().y = key.y;
    column_index_.insert(column_key, c);
  }
  pieces_[i].key = key;
  pieces_[i].column = c;
  // Empty until computed: what it gains is counted into the column then (recompute).
  columns_[c].pieces.push_back(i);
}

void MapOutputCache::dropPiece(uint32_t i) {
  if (i >= pieces_.size() || pieces_[i].column == kNoColumn) return;
  regather();  // with_cells_ changes
  Piece& piece = pieces_[i];
  occupied_cells_ -= piece.shown_cells;
  unlist(i);
  Column& col = columns_[piece.column];
  countPiece(&col, piece.band_occupied, piece.band_free, 0, 0);
  col.pieces.erase(std::find(col.pieces.begin(), col.pieces.end(), i));
  markDirty(piece.column);
  bounds_stale_ = true;  // the column's bounds may shrink
  piece = Piece();
}

fragg::BlockChange MapOutputCache::refreshOn(const fragg::OccupancyModel& model) const {
  if (options_.refresh_on != fragg::BlockChange::kMasks) return options_.refresh_on;
  // Every cell observed has left the unknown band at its first update (OctoMap's hit and miss
  // probabilities with the default band do): becoming observed then changes a mask, and the
  // change log lists every block whose outputs can change.
  const int16_t first_hit = model.updated(fragg::kUnobservedLogOdds, true);
  const int16_t first_miss = model.updated(fragg::kUnobservedLogOdds, false);
  const bool leaves_band = first_hit > model.occupied_above_fx && first_miss < model.free_below_fx;
  return leaves_band ? fragg::BlockChange::kMasks : fragg::BlockChange::kState;
}

template <class View>
void MapOutputCache::listChanges(const fragg::Map& map, const View& blocks, bool full,
                                 bool masks_suffice, bool keys_only, std::vector<Source>* out) {
  // A mirror holds no cells: its blocks always come with their masks.
  constexpr bool kMirror = !std::is_same_v<View, fragg::BlockView>;
  const fragg::BlockChange refresh_on = refreshOn(map.model());
  std::vector<Source>& refresh = *out;
  refresh.clear();
  const auto add = [&](fragg::BlockIndex slot, bool with_masks) {
    refresh.push_back(
        {slot, blocks.keyAt(slot), with_masks && !keys_only ? &blocks.masksAt(slot) : nullptr});
  };
  if (full) {
    const std::vector<fragg::BlockIndex> slots = blocks.allSlots();
    refresh.reserve(slots.size());
    for (const fragg::BlockIndex i : slots) add(i, kMirror);
  } else if (!options_.hide_speckles) {
    // Several revisions since the last update (a throttled map_rate): the change log names a
    // block once per revision it changed in (ten W1 clouds at 5 cm: 48-54 k blocks each, 87 k
    // distinct), and de-duplicating the records costs more than a walk over the blocks'
    // stamps in slot order. kState lists the blocks of kMasks and those whose cells moved
    // within the unknown band (recomputed from their masks all the same). The CUDA backend
    // stamps state_at with every change, so there the log serves.
    const bool walk = !kMirror && masks_suffice && map.revision() - revision_ > kLogRevisions &&
                      std::strcmp(map.backendName(), "cpu") == 0;
    blocks.changedSlotsSince(revision_, walk ? fragg::BlockChange::kState : refresh_on, &slots_);
    refresh.reserve(slots_.size());
    for (const fragg::BlockIndex i : slots_) add(i, masks_suffice);
  } else {
    // A cell's speckle state follows its neighbours: the blocks around a change too.
    const std::vector<fragg::BlockKey> changed = blocks.changedSince(revision_, refresh_on);
    fragg::BlockKeyTable around;
    around.reserve(changed.size() * 4);
    for (const fragg::BlockKey& k : changed) {
      for (int dz = -1; dz <= 1; ++dz) {
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const fragg::BlockKey n{k.x + dx, k.y + dy, k.z + dz};
            if (around.find(n) != fragg::BlockKeyTable::kNone) continue;
            around.insert(n, 0);
            // A missing neighbour has no piece (erasing a block changes the view epoch).
            const fragg::BlockIndex slot = blocks.slotOf(n);
            if (slot != fragg::kNoBlock) add(slot, true);
          }
        }
      }
    }
    std::sort(refresh.begin(), refresh.end(),
              [](const Source& x, const Source& y) { return x.slot < y.slot; });
  }
}

OutputCacheUpdate MapOutputCache::update(const fragg::Map& map) {
  return refresh(map, 0.0, 0.0, true, false);
}

OutputCacheUpdate MapOutputCache::advance(const fragg::Map& map, double now_s, double period_s,
                                          bool with_grid, bool gather_cloud) {
  return refresh(map, now_s, period_s, with_grid || period_s <= 0.0, gather_cloud);
}

OutputCacheUpdate MapOutputCache::refresh(const fragg::Map& map, double now_s, double period_s,
                                          bool with_grid, bool gather_cloud) {
  OutputCacheUpdate out;
  auto t0 = std::chrono::steady_clock::now();
  const uint64_t revision = map.revision();
  out.full = !valid_ || map.viewEpoch() != epoch_ || revision < revision_ ||
             map.resolution() != resolution_m_;
  resolution_m_ = map.resolution();  // the gathered centres' (writeCenters)
  // Blocks come with their masks where the change log lists every change of outputs (kMasks);
  // a mirror serves only then (it holds no cells to list kState changes by).
  const bool masks_serve =
      refreshOn(map.model()) == fragg::BlockChange::kMasks && options_.masks_where_settled;
  const bool mirrored = mirror_ != nullptr && masks_serve;
  // The pieces are indexed by the mirror's slots: a mirror rebuilt (by this cache or another
  // reader) rebuilds them.
  if (mirrored && mirror_->generation() != mirror_generation_) out.full = true;
  // Paced, the changes are listed at a publication (with_grid) only, and recomputed in even
  // shares over the clouds of the next period.
  bool paced = period_s > 0.0 && !out.full;
  const bool list = !paced || with_grid || !advanced_;
  if (mirrored && list) {
    mirror_->sync(map);
    if (mirror_->generation() != mirror_generation_) {  // rebuilt just now
      out.full = true;
      paced = false;
    }
  }
  // The blocks to recompute, and those that left the map. With the change log (kMasks) a block
  // comes with its state masks (its cells are read only where the grid's bounds need them).
  const bool masks_suffice = (!out.full || mirrored) && masks_serve;
  if (mirrored) {
    // Shares read the mirror as the last sync left it; cells, where the grid's bounds need
    // them, from the host's copy (no write-back).
    refreshOver(map, *mirror_, map.hostBlockView(), now_s, period_s, paced, list, with_grid,
                gather_cloud, masks_suffice, t0, &out);
    mirror_generation_ = mirror_->generation();
  } else {
    // A listing reads the whole map (a CUDA map's changes written back first); a share
    // recomputes blocks listed then, from the host's copy as it stands: a CUDA map is written
    // back once a period, not at every cloud (the same cells on a CPU map).
    const fragg::BlockView blocks = list ? map.blockView() : map.hostBlockView();
    refreshOver(map, blocks, blocks, now_s, period_s, paced, list, with_grid, gather_cloud,
                masks_suffice, t0, &out);
  }
  return out;
}

template <class View>
void MapOutputCache::refreshOver(const fragg::Map& map, const View& blocks,
                                 const fragg::BlockView& cells, double now_s, double period_s,
                                 bool paced, bool list, bool with_grid, bool gather_cloud,
                                 bool masks_suffice, std::chrono::steady_clock::time_point t0,
                                 OutputCacheUpdate* update) {
  OutputCacheUpdate& out = *update;
  const uint64_t revision = revisionOf(map, blocks);  // a mirror's may lag (acceptLag)
  for (const uint32_t c : dirty_) columns_[c].dirty = false;
  dirty_.clear();
  if (out.full) {
    pieces_.clear();
    with_cells_.clear();
    columns_.clear();
    column_index_.clear();
    undrawn_.clear();  // their columns are gone: the grid is drawn whole
    queue_.clear();
    queue_head_ = 0;
    occupied_cells_ = 0;
    seen_valid_ = false;
    bounds_stale_ = false;
    regather();
  }
  // First what was queued and is due: at a listing all of it (what the shares left: nothing,
  // when they kept up), else this cloud's share: what is left over the clouds left until the
  // list is kRecomputedBy of a period old.
  size_t take = queuedBlocks();
  const double interval_s = paced ? std::clamp(now_s - last_advance_s_, 1e-6, period_s) : 0.0;
  // Shares of `n` over the clouds left until `until_s` (this one included; at least one).
  const auto share = [&](size_t n, double until_s) {
    const double clouds_left = std::max(1.0, std::floor((until_s - now_s) / interval_s + 1e-6));
    return static_cast<size_t>(std::ceil(static_cast<double>(n) / clouds_left));
  };
  if (paced && !list && take > 0) take = share(take, queued_since_s_ + kRecomputedBy * period_s);
  if (paced) {
    last_advance_s_ = now_s;
    advanced_ = true;
  }
  std::vector<Source>& queued = sources_;
  queued.clear();
  std::vector<fragg::BlockIndex> gone;
  for (size_t q = queue_head_; q < queue_head_ + take; ++q) {
    const Queued& k = queue_[q];
    if (!blocks.holds(k.slot, k.key)) {
      // Left the map since it was listed: its piece goes (unless another block's is there).
      if (k.slot < pieces_.size() && pieces_[k.slot].key == k.key) gone.push_back(k.slot);
      continue;
    }
    queued.push_back({k.slot, k.key, masks_suffice ? &blocks.masksAt(k.slot) : nullptr});
  }
  queue_head_ += take;
  if (queue_head_ == queue_.size()) {
    queue_.clear();
    queue_head_ = 0;
  }
  for (const fragg::BlockIndex slot : gone) dropPiece(slot);
  out.list_ms += msSince(t0);
  recompute(map, blocks, cells, queued, masks_suffice, &out);
  // The queue recomputed: the pieces stay as they are until the next listing, and the clouds
  // until then gather them into the next publication's cloud message (its share: what is left
  // over the clouds left until the list is a period old, the publication's included).
  if (paced && !list && gather_cloud && queuedBlocks() == 0 && gathered_ < with_cells_.size()) {
    t0 = std::chrono::steady_clock::now();
    const size_t before = gathered_bytes_;
    const size_t pieces = share(with_cells_.size() - gathered_, queued_since_s_ + period_s);
    gatherCloud(pieces);
    out.pieces_gathered = pieces;
    out.bytes_gathered = gathered_bytes_ - before;
    out.gather_ms = msSince(t0);
  }
  // Then the changes since the last list: queued (paced), or recomputed now.
  t0 = std::chrono::steady_clock::now();
  std::vector<Source>& listed = sources_;  // the queue's share is recomputed
  listed.clear();
  if (list) listChanges(map, blocks, out.full, masks_suffice, paced, &listed);
  if (paced && list) {
    queue_.reserve(queue_.size() + listed.size());
    for (const Source& s : listed) queue_.push_back({s.slot, s.key});
    queued_since_s_ = now_s;
    listed.clear();
  }
  out.list_ms += msSince(t0);
  recompute(map, blocks, cells, listed, masks_suffice, &out);
  out.blocks_queued = queuedBlocks();
  t0 = std::chrono::steady_clock::now();
  for (const uint32_t c : dirty_) {
    Column& col = columns_[c];
    mergeBounds(&col);
    widenSeen(col);
    markUndrawn(c);
  }
  out.columns_merged += dirty_.size();
  refreshGrid(out.full, with_grid);
  valid_ = true;
  if (list) revision_ = revision;  // the changes up to it are in the pieces or queued
  epoch_ = map.viewEpoch();
  out.grid_ms = msSince(t0);
}

template <class View>
void MapOutputCache::recompute(const fragg::Map& map, const View& blocks,
                               const fragg::BlockView& cells, const std::vector<Source>& sources,
                               bool masks_suffice, OutputCacheUpdate* out) {
  if (sources.empty()) return;
  regather();  // pieces may change
  const auto t0 = std::chrono::steady_clock::now();
  // Each block's piece (new ones made first: pieces_ does not change while the pieces are
  // computed), then the pieces in parallel (read-only map, one piece per iteration), then the
  // sums in order.
  for (const Source& source : sources) pieceFor(source);  // a piece's index is its slot
  const auto made = std::chrono::steady_clock::now();
  std::vector<PieceDelta>& deltas = deltas_;
  deltas.assign(sources.size(), PieceDelta());
  const int64_t n = static_cast<int64_t>(sources.size());
  // The loop waits on memory (a piece and a block's masks, each a few cache lines at random
  // places): both are fetched a few iterations ahead.
  constexpr int64_t kAhead = 8;
#pragma omp parallel for schedule(dynamic, 256) if (n > 1024)
  for (int64_t j = 0; j < n; ++j) {
    if (j + kAhead < n) {
      const Piece* ahead = &pieces_[sources[j + kAhead].slot];
      __builtin_prefetch(ahead);
      __builtin_prefetch(ahead->shown.data());
      if (const fragg::BlockStateMasks* m = sources[j + kAhead].masks) {
        __builtin_prefetch(m->occupied);
        __builtin_prefetch(m->free);
      }
    }
    deltas[j] =
        computePiece(map, blocks, cells, sources[j], masks_suffice, &pieces_[sources[j].slot]);
  }
  const auto computed = std::chrono::steady_clock::now();
  int64_t occupied_delta = 0;
  for (size_t j = 0; j < sources.size(); ++j) {
    const PieceDelta& d = deltas[j];
    relist(sources[j].slot);
    occupied_delta += d.occupied;
    out->blocks_cells_read += d.cells_read;
    if (!d.column) continue;
    // The column's counts take the piece's change (no pass over its pieces); its bounds and
    // the grid's widen, unless the piece lost bounds (a scan removed): then the column's are
    // merged again from its pieces and the grid's recomputed.
    const Piece& piece = pieces_[sources[j].slot];
    Column& col = columns_[piece.column];
    countPiece(&col, d.occupied_before, d.free_before, piece.band_occupied, piece.band_free);
    markUndrawn(piece.column);
    ++out->columns_merged;
    if (d.bounds_shrank) {
      markDirty(piece.column);
      bounds_stale_ = true;
      continue;
    }
    widenColumn(&col, piece);
    widenSeen(col);
  }
  occupied_cells_ = static_cast<size_t>(static_cast<int64_t>(occupied_cells_) + occupied_delta);
  out->blocks_read += sources.size();
  out->pieces_ms += msSince(t0);
  out->pieces_made_ms += std::chrono::duration<double, std::milli>(made - t0).count();
  out->pieces_computed_ms += std::chrono::duration<double, std::milli>(computed - made).count();
  out->pieces_summed_ms += msSince(computed);
}

MapOutputCache::Tile& MapOutputCache::tileAt(int64_t x, int64_t y) {
  const fragg::BlockKey tile_key{static_cast<int32_t>(x >> kTileBits),
                                 static_cast<int32_t>(y >> kTileBits), 0};
  uint32_t t = tile_index_.find(tile_key);
  if (t == fragg::BlockKeyTable::kNone) {
    t = static_cast<uint32_t>(tiles_.size());
    tiles_.emplace_back().cells.fill(kUnknown);
    tile_index_.insert(tile_key, t);
  }
  return tiles_[t];
}

void MapOutputCache::drawColumn(const Column& col) {
  // A column's 8 x 8 cells lie in one tile (tiles are multiples of 8 cells, aligned).
  static_assert(kTileCells % fragg::kBlockSize == 0, "a column never straddles two tiles");
  const int64_t x0 = int64_t{col.x} * fragg::kBlockSize, y0 = int64_t{col.y} * fragg::kBlockSize;
  Tile& tile = tileAt(x0, y0);
  const int64_t tx = x0 & (kTileCells - 1), ty = y0 & (kTileCells - 1);
  for (int ly = 0; ly < fragg::kBlockSize; ++ly) {
    int8_t* row = tile.cells.data() + (ty + ly) * kTileCells + tx;
    for (int lx = 0; lx < fragg::kBlockSize; ++lx) {
      const int bit = lx + fragg::kBlockSize * ly;
      row[lx] = (col.occupied >> bit & 1) ? kOccupied : (col.free >> bit & 1) ? kFree : kUnknown;
    }
  }
}

void MapOutputCache::refreshGrid(bool all, bool draw) {
  // The observed cells' bounds (also for the next update's boundsSettled): widened as columns
  // change (observed cells stay observed), over every column again only after a piece left.
  if (bounds_stale_) {
    seen_valid_ = false;
    for (const Column& col : columns_) widenSeen(col);
    bounds_stale_ = false;
  }
  const bool empty = !seen_valid_;
  int64_t lo_x = seen_lo_x_, hi_x = seen_hi_x_, lo_y = seen_lo_y_, hi_y = seen_hi_y_;
  redraw_owed_ = redraw_owed_ || all;
  // The tiles do not depend on the bounds: the columns merged since the last draw are drawn at
  // once (a paced share draws its own, so a publication draws little), a whole redraw (after a
  // rebuild) at the next publication.
  if (redraw_owed_ && !draw) return;
  for (const uint32_t c : undrawn_) columns_[c].undrawn = false;
  undrawn_.swap(drawing_);
  undrawn_.clear();
  if (redraw_owed_) {
    // Every column again on tiles made unknown (their memory kept: no fresh pages).
    redraw_owed_ = false;
    for (Tile& tile : tiles_) tile.cells.fill(kUnknown);
    for (const Column& col : columns_) drawColumn(col);
  } else {
    // An emptied column is merged to unknown.
    for (const uint32_t c : drawing_) drawColumn(columns_[c]);
  }
  if (!draw) return;  // the published rectangle: at a publication (advance with_grid, update)
  if (empty) {
    grid_empty_ = true;
    grid_width_ = grid_height_ = 0;
    return;
  }
  if (options_.octomap_bounds) {
    const GridSpan x = octomapServerGridSpan(lo_x, hi_x, resolution_m_);
    const GridSpan y = octomapServerGridSpan(lo_y, hi_y, resolution_m_);
    lo_x = x.lo, hi_x = x.hi, lo_y = y.lo, hi_y = y.hi;
  }
  // Every drawn cell is observed, so it lies inside the bounds: cells of the tiles outside
  // them are unknown and not published.
  grid_empty_ = false;
  grid_min_x_ = static_cast<int32_t>(lo_x);
  grid_min_y_ = static_cast<int32_t>(lo_y);
  grid_width_ = hi_x - lo_x + 1;
  grid_height_ = hi_y - lo_y + 1;
}

void MapOutputCache::copyPublished(int8_t* dst) const {
  // Tile by tile: each tile's part of the rectangle row by row; no tile: unknown.
  const int64_t x_end = int64_t{grid_min_x_} + grid_width_;
  const int64_t y_end = int64_t{grid_min_y_} + grid_height_;
  const size_t row_bytes = static_cast<size_t>(grid_width_);
  for (int64_t y0 = grid_min_y_; y0 < y_end;) {
    const int64_t tile_y = y0 >> kTileBits;
    const int64_t y1 = std::min(y_end, (tile_y + 1) << kTileBits);
    for (int64_t x0 = grid_min_x_; x0 < x_end;) {
      const int64_t tile_x = x0 >> kTileBits;
      const int64_t x1 = std::min(x_end, (tile_x + 1) << kTileBits);
      const uint32_t t =
          tile_index_.find({static_cast<int32_t>(tile_x), static_cast<int32_t>(tile_y), 0});
      const size_t bytes = static_cast<size_t>(x1 - x0);
      for (int64_t y = y0; y < y1; ++y) {
        int8_t* out = dst + static_cast<size_t>(y - grid_min_y_) * row_bytes +
                      static_cast<size_t>(x0 - grid_min_x_);
        if (t == fragg::BlockKeyTable::kNone) {
          std::memset(out, kUnknown, bytes);
        } else {
          const int8_t* in = tiles_[t].cells.data() + (y & (kTileCells - 1)) * kTileCells +
                             (x0 & (kTileCells - 1));
          std::memcpy(out, in, bytes);
        }
      }
      x0 = x1;
    }
    y0 = y1;
  }
}

const sensor_msgs::PointCloud2& MapOutputCache::occupiedCloud(const std::string& frame_id,
                                                              const ::ros::Time& stamp) const {
  // The buffer outlives the message's other fields: within its capacity resizing writes at
  // most the new tail, so a publication does not fault in and zero a fresh buffer of the whole
  // map's size each time. Outgrown, it is replaced (nothing copied) with room for the map to
  // grow by half.
  std::vector<uint8_t> data = std::move(cloud_msg_.data);
  cloud_msg_ = packedXyzCloud(std::vector<float>(), frame_id, stamp);
  cloud_msg_.width = static_cast<uint32_t>(occupied_cells_);
  cloud_msg_.row_step = cloud_msg_.point_step * cloud_msg_.width;
  const size_t bytes = occupied_cells_ * 3 * sizeof(float);
  if (bytes > data.capacity()) {
    data = std::vector<uint8_t>();
    data.reserve(bytes + bytes / 2);
  }
  data.resize(bytes);
  uint8_t* dst = data.data();
  for (const uint32_t i : with_cells_) dst = writeCenters(pieces_[i], dst);
  cloud_msg_.data = std::move(data);
  return cloud_msg_;
}

void MapOutputCache::gatherCloud(size_t pieces) {
  uint8_t* payload =
      cloud_wire_.reserve(occupied_cells_ * 3 * sizeof(float), gathered_bytes_) + gathered_bytes_;
  const size_t end = std::min(with_cells_.size(), gathered_ + pieces);
  for (; gathered_ < end; ++gathered_) {
    uint8_t* const written = writeCenters(pieces_[with_cells_[gathered_]], payload);
    gathered_bytes_ += static_cast<size_t>(written - payload);
    payload = written;
  }
}

uint8_t* MapOutputCache::writeCenters(const Piece& piece, uint8_t* dst) const {
  // Map::centerOf's (voxelCenterM) as float, in the piece's cell order (x + 8 y + 64 z).
  const fragg::BlockKey& key = piece.key;
  for (int z = 0; z < fragg::kBlockSize; ++z) {
    for (uint64_t m = piece.shown[z]; m; m &= m - 1) {
      const fragg::VoxelKey k = fragg::voxelKeyOf(key, 64 * z + __builtin_ctzll(m));
      const float p[3] = {static_cast<float>(fragg::voxelCenterM(k.x, resolution_m_)),
                          static_cast<float>(fragg::voxelCenterM(k.y, resolution_m_)),
                          static_cast<float>(fragg::voxelCenterM(k.z, resolution_m_))};
      std::memcpy(dst, p, sizeof(p));
      dst += sizeof(p);
    }
  }
  return dst;
}

PreserializedCloud MapOutputCache::occupiedCloudWire(const std::string& frame_id,
                                                     const ::ros::Time& stamp) {
  gatherCloud(with_cells_.size() - gathered_);  // what the shares left (all after update())
  if (gathered_bytes_ != occupied_cells_ * 3 * sizeof(float))
    throw std::logic_error("output cache: the gathered cloud (" + std::to_string(gathered_bytes_) +
                           " bytes) is not the occupied cells' (" +
                           std::to_string(occupied_cells_) + ")");
  // The message's fields around its data, serialised by roscpp (a hundred bytes).
  sensor_msgs::PointCloud2 empty = packedXyzCloud(std::vector<float>(), frame_id, stamp);
  empty.width = static_cast<uint32_t>(occupied_cells_);
  empty.row_step = empty.point_step * empty.width;
  const ::ros::SerializedMessage fields = ::ros::serialization::serializeMessage(empty);
  PreserializedCloud out{cloud_wire_.finish(fields, sizeof(empty.is_dense), gathered_bytes_)};
  regather();  // the next message: another buffer, gathered from the start
  return out;
}

PreserializedGrid MapOutputCache::projectedMapWire(const std::string& frame_id,
                                                   const ::ros::Time& stamp) {
  const nav_msgs::OccupancyGrid empty = gridWithoutData(frame_id, stamp);
  const size_t bytes = grid_empty_ ? 0 : static_cast<size_t>(grid_width_ * grid_height_);
  if (bytes > 0) copyPublished(reinterpret_cast<int8_t*>(grid_wire_.reserve(bytes, 0)));
  const ::ros::SerializedMessage fields = ::ros::serialization::serializeMessage(empty);
  return PreserializedGrid{grid_wire_.finish(fields, 0, bytes)};
}

nav_msgs::OccupancyGrid MapOutputCache::gridWithoutData(const std::string& frame_id,
                                                        const ::ros::Time& stamp) const {
  nav_msgs::OccupancyGrid grid;
  grid.header.frame_id = frame_id;
  grid.header.stamp = stamp;
  grid.info.map_load_time = stamp;
  grid.info.resolution = static_cast<float>(resolution_m_);
  grid.info.origin.orientation.w = 1.0;
  if (grid_empty_) return grid;
  grid.info.width = static_cast<uint32_t>(grid_width_);
  grid.info.height = static_cast<uint32_t>(grid_height_);
  grid.info.origin.position.x = grid_min_x_ * resolution_m_;
  grid.info.origin.position.y = grid_min_y_ * resolution_m_;
  return grid;
}

nav_msgs::OccupancyGrid MapOutputCache::projectedMap(const std::string& frame_id,
                                                     const ::ros::Time& stamp) const {
  nav_msgs::OccupancyGrid grid = gridWithoutData(frame_id, stamp);
  if (grid_empty_) return grid;
  grid.data.resize(static_cast<size_t>(grid_width_ * grid_height_));
  copyPublished(grid.data.data());
  return grid;
}

}  // namespace fragg::ros
