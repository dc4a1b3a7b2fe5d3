// Read-only access to a map's blocks (Map::blockView): keys and cells, never the storage's
// bookkeeping. Taken once, it serves any number of lookups from any number of threads
// without locking; it stays valid until the map is next changed (hold the map's read lock).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "fragg_map/block_map.h"

namespace fragg {

/// Which changes BlockView::changedSince() reports.
enum class BlockChange {
  kAny,       ///< any cell's value
  kOccupied,  ///< which cells are occupied (a cell crossed the occupied threshold either way)
  kState,     ///< any cell's state: observed or not, free / occupied / unknown band
  /// the block's state masks (a cell became or stopped being occupied or free): answered from
  /// the change log the writers keep, without a walk over the blocks while it reaches back
  kMasks,
};

/// A block as readers see it: its key and cells.
using BlockVisitor = std::function<void(const BlockKey& key, const Block& block)>;

struct BlockRef {
  BlockKey key;
  const Block* block;
};

/// Map revisions of a block's last changes (0: never changed, or no such block).
struct BlockStamps {
  uint64_t changed_at = 0;   ///< any cell's value
  uint64_t occupied_at = 0;  ///< which cells are occupied
  uint64_t state_at = 0;     ///< any cell's state (BlockChange::kState)
  uint64_t masks_at = 0;     ///< the state masks (BlockChange::kMasks)
};

class BlockView {
 public:
  explicit BlockView(const BlockMap& blocks) : blocks_(&blocks) {}
  /// A view that holds `pin` while it (or a copy) lives (Map::hostBlockView: the host's blocks
  /// are not written back meanwhile).
  BlockView(const BlockMap& blocks, std::shared_ptr<const void> pin)
      : blocks_(&blocks), pin_(std::move(pin)) {}

  size_t size() const { return blocks_->size(); }
  bool empty() const { return blocks_->empty(); }
  /// nullptr when the block does not exist (all its cells unknown).
  const Block* findBlock(const BlockKey& key) const { return blocks_->findBlock(key); }
  const Cell* findCell(const VoxelKey& key) const { return blocks_->findCell(key); }
  /// The block's cell-state masks (state_masks.h), nullptr when the block does not exist (all
  /// its cells unknown). Kept current by every write: no cell needs to be read for states.
  [[nodiscard]] const BlockStateMasks* findMasks(const BlockKey& key) const {
    const BlockIndex i = blocks_->find(key);
    return i == kNoBlock ? nullptr : &blocks_->masks(i);
  }
  /// Calls fn(key, block) for every block, in unspecified order.
  void forEach(const BlockVisitor& fn) const;
  /// Calls fn(key, block) for every block whose key lies in [lo, hi] (inclusive); the cost
  /// follows the blocks there, not the box volume.
  void forEachIn(const BlockKey& lo, const BlockKey& hi, const BlockVisitor& fn) const;
  /// Every block, in unspecified order (for parallel loops).
  std::vector<BlockRef> all() const;
  /// The blocks whose key lies in [lo, hi].
  std::vector<BlockRef> in(const BlockKey& lo, const BlockKey& hi) const;
  /// Keys of the blocks whose cells changed (`what`) after map revision `revision`, in
  /// unspecified order. Removed blocks are not listed.
  std::vector<BlockKey> changedSince(uint64_t revision, BlockChange what = BlockChange::kAny) const;
  /// The same blocks with their cells (no second look-up per key).
  std::vector<BlockRef> changedRefsSince(uint64_t revision,
                                         BlockChange what = BlockChange::kAny) const;
  BlockStamps stamps(const BlockKey& key) const;

  // Slots: the blocks' places in the map's storage (BlockIndex). A block keeps its slot until
  // it leaves the map; a later block may take the slot over (compare keyAt with the key kept).
  // Reading by slot costs no look-up, and ascending slots read the storage in order: readers
  // that keep per-block records across updates index them by slot.
  /// Slots in use or free: every block's slot is below it.
  [[nodiscard]] size_t slotCount() const { return blocks_->slotCount(); }
  /// The slot of block `key`, kNoBlock when it does not exist.
  [[nodiscard]] BlockIndex slotOf(const BlockKey& key) const { return blocks_->find(key); }
  /// Whether `slot` (< slotCount()) holds the block `key` now.
  [[nodiscard]] bool holds(BlockIndex slot, const BlockKey& key) const {
    return blocks_->meta(slot).key == key && blocks_->liveAt(slot);
  }
  /// The key of the block in `slot` (< slotCount()); BlockMap::kFreedSlotKey for a free slot.
  [[nodiscard]] const BlockKey& keyAt(BlockIndex slot) const { return blocks_->meta(slot).key; }
  /// The cells of the block in `slot` (a live slot).
  [[nodiscard]] const Block& blockAt(BlockIndex slot) const { return blocks_->block(slot); }
  /// The state masks of the block in `slot` (a live slot).
  [[nodiscard]] const BlockStateMasks& masksAt(BlockIndex slot) const {
    return blocks_->masks(slot);
  }
  /// Slots of every block, ascending.
  [[nodiscard]] std::vector<BlockIndex> allSlots() const;
  /// Slots of the blocks changed (`what`) after map revision `revision`, ascending: from the
  /// change log for kMasks while it reaches back, else from one walk over the blocks' stamps
  /// in storage order (sequential reads, no look-up per block).
  [[nodiscard]] std::vector<BlockIndex> changedSlotsSince(
      uint64_t revision, BlockChange what = BlockChange::kAny) const;
  /// The same into `out` (its memory kept: a caller listing every period reuses its pages).
  void changedSlotsSince(uint64_t revision, BlockChange what, std::vector<BlockIndex>* out) const;
  /// Exact bounds of observed cells.
  KeyBounds observedBounds() const { return blocks_->observedBounds(); }

 private:
  const BlockMap* blocks_;
  std::shared_ptr<const void> pin_;  ///< HostViewGate::Pin, or none
};

}  // namespace fragg
