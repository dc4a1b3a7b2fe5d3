// A host copy of a map's block keys and state masks for the server's incremental outputs
// (markers, occupied cloud, projected map), brought up to date from the map's changed-block list
// (Map::masksChangedSince: the host change log and, on a CUDA map, a compaction over the device
// pool) without reading a cell and without writing the device's blocks back. On a CUDA map the
// outputs' take-ins read Map::blockView(), which copies every block changed on the device back
// to the host first (~2.3 KB a block, tens of thousands a LiDAR second); the mirror copies
// their masks (128 B) instead. It offers the slot interface of BlockView that the outputs use
// (slots are the mirror's own, dense, kept until a rebuild), plus the blocks' masks by key.
// A change of the map's view (Map::viewEpoch: erase, clear_bbx, truncate, load, paging), a
// revision that went back, or a change log that no longer reaches back rebuilds it from
// Map::blockView(). Not thread-safe to sync; const lookups may run in parallel between syncs.
#pragma once

#include <cstdint>
#include <vector>

#include "fragg_map/block_key_table.h"
#include "fragg_map/block_view.h"
#include "fragg_map/map.h"
#include "fragg_map/ros/chunked_array.h"
#include "fragg_map/state_masks.h"

namespace fragg::ros {

class MaskMirror {
 public:
  /// What the last sync() did.
  struct SyncStats {
    bool rebuilt = false;         ///< read whole from Map::blockView()
    size_t listed = 0;            ///< blocks the changed-block list named (0 after a rebuild)
    size_t added = 0;             ///< blocks new to the mirror
    double seconds = 0.0;         ///< wall time of the sync
    double list_seconds = 0.0;    ///< of it, Map::masksChangedSince (or the rebuild's blockView)
    double update_seconds = 0.0;  ///< the held blocks' update (after the list)
    double add_seconds = 0.0;     ///< the new blocks added (after the update)
    uint64_t lagged = 0;  ///< left this many revisions behind the map (acceptLag), not synced
  };

  /// Brings the mirror up to date with `map` (held under its read lock); nothing to do when it
  /// is at the map's revision and view already. Blocks whose masks changed get the map's
  /// revision as their stamp (kOccupied: when their occupied cells changed).
  /// With a lag accepted (acceptLag), a mirror at the map's view epoch and resolution that is
  /// at most that many revisions behind is left as it is (SyncStats::lagged says so).
  const SyncStats& sync(const fragg::Map& map);
  /// Lets sync() leave the mirror up to `revisions` map revisions behind the map (0, the
  /// default: every sync brings it up to the map's revision). For a server that brings it up
  /// to date between clouds: a cloud's outputs then read it as that sync left it, one insertion
  /// old. Readers keep the mirror's revision as what they have seen, not the map's.
  void acceptLag(uint64_t revisions) { accepted_lag_ = revisions; }
  /// The lag acceptLag set.
  [[nodiscard]] uint64_t acceptedLag() const { return accepted_lag_; }
  /// Forgets everything: the next sync rebuilds.
  void invalidate() { valid_ = false; }
  [[nodiscard]] bool valid() const { return valid_; }
  /// The map revision and view epoch the mirror is at.
  [[nodiscard]] uint64_t revision() const { return revision_; }
  [[nodiscard]] uint64_t viewEpoch() const { return epoch_; }
  /// Blocks held.
  [[nodiscard]] size_t size() const { return table_.size(); }
  /// Cells free or occupied in the held masks (kept as they change: no walk). Observed cells
  /// in the unknown band are not among them (Map::memory's known_voxels counts those too).
  [[nodiscard]] uint64_t knownCells() const { return known_cells_; }
  /// Counts the rebuilds: the slots of one generation are not those of another (a reader that
  /// keeps records by slot starts over when it changes; a rebuild stamps every block changed).
  [[nodiscard]] uint64_t generation() const { return generation_; }

  // BlockView's slot interface (the same meaning, the mirror's slots).
  /// Slots in use: every block's slot is below it.
  [[nodiscard]] size_t slotCount() const { return keys_.size(); }
  /// The slot of block `key`, kNoBlock when the mirror does not hold it.
  [[nodiscard]] fragg::BlockIndex slotOf(const fragg::BlockKey& key) const {
    const uint32_t s = table_.find(key);
    return s == fragg::BlockKeyTable::kNone ? fragg::kNoBlock : s;
  }
  /// Whether `slot` (< slotCount()) holds the block `key`.
  [[nodiscard]] bool holds(fragg::BlockIndex slot, const fragg::BlockKey& key) const {
    return keys_[slot] == key;
  }
  /// The key of the block in `slot` (< slotCount()).
  [[nodiscard]] const fragg::BlockKey& keyAt(fragg::BlockIndex slot) const { return keys_[slot]; }
  /// The state masks of the block in `slot` as of the last sync.
  [[nodiscard]] const fragg::BlockStateMasks& masksAt(fragg::BlockIndex slot) const {
    return masks_[slot];
  }
  /// The block's masks, nullptr when the mirror does not hold it (no cell of it observed, as
  /// of the last sync).
  [[nodiscard]] const fragg::BlockStateMasks* findMasks(const fragg::BlockKey& key) const {
    const uint32_t s = table_.find(key);
    return s == fragg::BlockKeyTable::kNone ? nullptr : &masks_[s];
  }
  /// Whether the mirror holds block `key`.
  [[nodiscard]] bool contains(const fragg::BlockKey& key) const {
    return table_.find(key) != fragg::BlockKeyTable::kNone;
  }
  /// Slots of every block, ascending.
  [[nodiscard]] std::vector<fragg::BlockIndex> allSlots() const;
  /// Slots of the blocks whose masks (kMasks, kState, kAny) or occupied cells (kOccupied)
  /// changed after map revision `revision`, ascending (a walk over the stamps).
  void changedSlotsSince(uint64_t revision, fragg::BlockChange what,
                         std::vector<fragg::BlockIndex>* out) const;
  /// Their keys.
  [[nodiscard]] std::vector<fragg::BlockKey> changedSince(uint64_t revision,
                                                          fragg::BlockChange what) const;

 private:
  void rebuild(const fragg::Map& map);
  /// Every listed block (listed_keys_, listed_masks_) set, stamping what changed with
  /// `revision`: the held ones updated in parallel, then the new ones added in the list's order.
  void applyListed(uint64_t revision);
  /// Sets the masks of the block in slot `s`, stamping what changed with `revision`; returns
  /// the change of its known cells.
  int64_t update(uint32_t s, const fragg::BlockStateMasks& masks, uint64_t revision);

  bool valid_ = false;
  uint64_t generation_ = 0;
  uint64_t revision_ = 0;
  uint64_t epoch_ = 0;
  uint64_t accepted_lag_ = 0;  ///< acceptLag
  double resolution_m_ = 0.0;
  fragg::BlockKeyTable table_;  ///< key -> slot
  // By slot; they grow in chunks (a sync that adds blocks copies none of those held).
  ChunkedArray<fragg::BlockKey> keys_;
  ChunkedArray<fragg::BlockStateMasks> masks_;
  ChunkedArray<uint64_t> masks_at_;     ///< revision of the sync that last changed the masks
  ChunkedArray<uint64_t> occupied_at_;  ///< the same for the occupied cells
  // The changed-block list's buffers, kept between syncs (their pages stay resident).
  std::vector<fragg::BlockKey> listed_keys_;
  std::vector<fragg::BlockStateMasks> listed_masks_;
  std::vector<uint32_t> listed_slots_;  ///< applyListed: each listed key's slot or kNone
  SyncStats stats_;
  uint64_t known_cells_ = 0;  ///< knownCells()
};

/// The map revision whose changes `view` shows: the map's own view is at the map's revision.
[[nodiscard]] inline uint64_t revisionOf(const fragg::Map& map, const fragg::BlockView& /*view*/) {
  return map.revision();
}
/// A mask mirror is at the revision of its last sync (it may lag: MaskMirror::acceptLag).
[[nodiscard]] inline uint64_t revisionOf(const fragg::Map& /*map*/, const MaskMirror& mirror) {
  return mirror.revision();
}

}  // namespace fragg::ros
