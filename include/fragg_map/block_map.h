// The host map: block key -> block, blocks in an arena of fixed-size chunks (stable
// addresses, so the CUDA backend can pin them). Unobserved space has no block.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <unordered_map>
#include <vector>

#include "fragg_map/block_key_table.h"
#include "fragg_map/cell.h"
#include "fragg_map/change_log.h"
#include "fragg_map/culling.h"
#include "fragg_map/key.h"
#include "fragg_map/state_masks.h"

namespace fragg {

using BlockIndex = uint32_t;
constexpr BlockIndex kNoBlock = 0xffffffffu;

/// Where the arena gets its chunks from: plain aligned memory by default; the CUDA backend
/// installs a pinned-memory allocator.
class ChunkAllocator {
 public:
  virtual ~ChunkAllocator() = default;
  virtual void* allocate(size_t bytes) = 0;
  virtual void deallocate(void* p, size_t bytes) = 0;
  virtual const char* name() const = 0;
  /// Whether whole free pages of a chunk may be handed back to the system (madvise: they read
  /// zero when touched again); pinned memory may not.
  virtual bool pagesReleasable() const { return false; }
};
std::shared_ptr<ChunkAllocator> plainChunkAllocator();

struct BlockMeta {
  BlockKey key;
  uint64_t changed_at = 0;  ///< map revision of the last change (for incremental publishing)
  /// Map revision of the last change that may have changed which cells are occupied (a cell
  /// crossed the occupied threshold either way); <= changed_at. Occupied-cell markers need
  /// only the blocks with this newer than their last update.
  uint64_t occupied_at = 0;
  /// Map revision of the last change that may have changed a cell's state as readers see it:
  /// observed or not, and free / occupied / in the unknown band (OccupancyModel::state);
  /// occupied_at <= state_at <= changed_at. Outputs drawn from states alone (occupied cloud,
  /// projected map, free markers) need only these blocks: most of a scan's changes are free
  /// cells getting freer, which change changed_at only. Backends may set it more often than
  /// needed (the CUDA backend sets it with changed_at), never less.
  uint64_t state_at = 0;
  /// Map revision of the last change of the block's state masks (a cell became or stopped
  /// being occupied or free); <= state_at. Set with a record in the map's change log
  /// (BlockMap::noteMasksChanged), so that readers find these blocks without a walk.
  uint64_t masks_at = 0;
  /// Equal to changed_at while every cell of the block sits at the occupancy model's lower
  /// clamp (set by the CPU backend's update; any other value means "not known"). A miss changes
  /// nothing in such a block, so the ray pass skips its free cells (see freeSaturated()).
  uint64_t free_saturated_at = kNotSaturated;
  CullMemory cull;

  static constexpr uint64_t kNotSaturated = ~uint64_t{0};
  /// Every cell at the lower clamp as of the block's last change. Writers other than the CPU
  /// update move changed_at on and so end this without knowing about it.
  bool freeSaturated() const { return free_saturated_at == changed_at; }
};

/// Inclusive voxel-key bounds of the observed map.
struct KeyBounds {
  bool empty = true;
  VoxelKey min, max;
};

class BlockMap {
 public:
  static constexpr size_t kBlocksPerChunk = 1024;  // 2 MiB of cells per chunk

  explicit BlockMap(std::shared_ptr<ChunkAllocator> allocator = plainChunkAllocator());
  ~BlockMap();
  BlockMap(const BlockMap&) = delete;
  BlockMap& operator=(const BlockMap&) = delete;
  BlockMap(BlockMap&&) noexcept;
  BlockMap& operator=(BlockMap&&) noexcept;

  /// Lookups return kNoBlock / nullptr when the block does not exist. Thread-safe with other
  /// lookups, not with insertions or erasures.
  BlockIndex find(const BlockKey& key) const;
  const Block* findBlock(const BlockKey& key) const;
  Block* findBlock(const BlockKey& key);
  const Cell* findCell(const VoxelKey& key) const;

  /// Returns the block's index, creating an all-unobserved block when it is missing. With
  /// `initialise` false a new block's cells are left for the caller to write (the CPU
  /// backend fills new blocks in parallel).
  BlockIndex findOrCreate(const BlockKey& key, bool* created = nullptr, bool initialise = true);
  /// Makes room for `n` more blocks in the index.
  void reserve(size_t n) { index_.reserve(index_.size() + n); }
  /// Sizes the per-block arrays (metadata, state masks, free list) and the index once for
  /// `n` blocks, so that they do not grow while the map holds at most `n` blocks. Growth by
  /// doubling leaves the old arrays with the allocator (resident in a long-running process):
  /// a map under a paging budget reserves its budget's block count instead. Untouched
  /// capacity costs address space, not resident memory (except the index, whose slots are
  /// written when it is sized). Returns the block count the arrays now hold without growing.
  size_t reserveSlots(size_t n);
  void erase(const BlockKey& key);
  /// Erases every block of `keys` (missing ones are skipped): the same as erasing them one by
  /// one, with each coarse-index list rewritten once (a paging round erases tens of
  /// thousands of blocks, hundreds from the same list).
  void erase(const std::vector<BlockKey>& keys);
  void clear();

  Block& block(BlockIndex i) { return chunks_[i / kBlocksPerChunk][i % kBlocksPerChunk]; }
  const Block& block(BlockIndex i) const {
    return chunks_[i / kBlocksPerChunk][i % kBlocksPerChunk];
  }
  BlockMeta& meta(BlockIndex i) { return meta_[i]; }
  /// Slots of the per-block arrays, in use or free: every block's index is below it.
  [[nodiscard]] size_t slotCount() const { return meta_.size(); }
  /// Whether slot `i` (< slotCount()) holds a block: an erased slot's metadata keeps
  /// kFreedSlotKey (and no stamps) until findOrCreate hands it to another block.
  [[nodiscard]] bool liveAt(BlockIndex i) const { return meta_[i].key != kFreedSlotKey; }
  /// The key of free slots' metadata: no block has it (block keys are voxel keys >> 3).
  static constexpr BlockKey kFreedSlotKey{INT32_MIN, INT32_MIN, INT32_MIN};
  const BlockMeta& meta(BlockIndex i) const { return meta_[i]; }
  /// The block's cell-state masks (state_masks.h). A new block's are all unknown; whoever
  /// writes cells keeps them equal to stateMasksOf(block(i), the map's model).
  BlockStateMasks& masks(BlockIndex i) { return masks_[i]; }
  const BlockStateMasks& masks(BlockIndex i) const { return masks_[i]; }
  /// Recomputes the masks of the blocks `indices` from their cells with `model`, in parallel:
  /// for writers that replace whole blocks (loading, paging in).
  void recomputeMasks(const std::vector<BlockIndex>& indices, const OccupancyModel& model);
  /// The same for every live block.
  void recomputeAllMasks(const OccupancyModel& model);
  /// The masks of block `i` changed at map revision `revision`: stamps masks_at and records
  /// the key in the change log (once per block and revision: repeated calls are cheap).
  void noteMasksChanged(BlockIndex i, uint64_t revision) {
    BlockMeta& m = meta_[i];
    if (m.masks_at >= revision) return;
    m.masks_at = revision;
    changes_.record(revision, m.key, i);
  }
  /// Keys of the live blocks whose masks changed after map revision `revision`, from the change
  /// log (no walk over the map); false (nothing written) when the log no longer reaches back
  /// that far.
  [[nodiscard]] bool masksChangedSince(uint64_t revision, std::vector<BlockKey>* out) const;
  /// The order of a list of changed blocks: the change log's (each block where it first
  /// comes), or ascending slots (the metadata's storage order, for callers that walk it).
  enum class ListOrder { kLog, kSlots };
  /// The same blocks as indices (one lookup a block, for callers that read them next).
  [[nodiscard]] bool masksChangedSince(uint64_t revision, std::vector<BlockIndex>* out,
                                       ListOrder order = ListOrder::kLog) const;
  [[nodiscard]] const BlockChangeLog& changeLog() const { return changes_; }

  size_t size() const { return index_.size(); }
  /// Block slots of the arena, and how many of them are free (left by erased blocks; new
  /// blocks take those first).
  size_t slots() const { return meta_.size(); }
  size_t freeSlots() const { return free_.size(); }
  /// Orders the free slots so that the next blocks take them lowest first. After many
  /// erasures in no particular order (a paging round's victims) the blocks one scan creates
  /// then sit in runs of neighbouring slots, as in a map that only grows, instead of spread
  /// over the arena (its cells and metadata are read with every ray that enters them).
  void orderFreeSlots();
  bool empty() const { return index_.empty(); }

  /// Calls `fn(index)` for every live block whose key lies in [lo, hi] (inclusive), using the
  /// coarse spatial index so the cost follows the blocks there, not the box volume.
  void forEachInBox(const BlockKey& lo, const BlockKey& hi,
                    const std::function<void(BlockIndex)>& fn) const;
  /// Every live block, in unspecified order.
  void forEach(const std::function<void(BlockIndex)>& fn) const;
  /// Calls `fn(blocks)` once for each cell of the coarse spatial index (kBlockSize^3 blocks: a
  /// block key >> kBlockBits) with the live blocks in it, cells and blocks in unspecified
  /// order: a pass over every block grouped by place without a look-up per block.
  void forEachCoarseCell(const std::function<void(const std::vector<BlockIndex>&)>& fn) const;

  /// Exact bounds of observed cells (reads every cell of every block).
  KeyBounds observedBounds() const;

  size_t hostBytes() const;

  /// Hands the memory pages that hold only free blocks back to the system (paging out leaves
  /// the arena with holes the size of the blocks that left), in runs of at least 64 KiB (a
  /// call to the system for each shorter run cost more than the pages are worth); no-op for an
  /// allocator whose pages cannot be released. Returns the bytes released by this call.
  size_t releaseFreePages();

 private:
  /// Puts slot `i` on the free list, its metadata marked free (kFreedSlotKey, no stamps).
  void freeSlot(BlockIndex i);
  /// masksChangedSince by the slots the change log recorded (no look-up by key): false (`out`
  /// partly written) when a block recorded since was erased; the caller looks the keys up.
  bool slotsOfRecordsServe(uint64_t revision, std::vector<BlockIndex>* out, ListOrder order) const;
  struct SuperKeyHash {
    size_t operator()(const BlockKey& k) const noexcept { return BlockKeyHash()(k); }
  };
  static BlockKey superKeyOf(const BlockKey& b) {
    return {b.x >> kBlockBits, b.y >> kBlockBits, b.z >> kBlockBits};
  }

  std::shared_ptr<ChunkAllocator> allocator_;
  std::vector<Block*> chunks_;
  std::vector<BlockMeta> meta_;
  std::vector<BlockStateMasks> masks_;  ///< parallel to meta_
  BlockChangeLog changes_;              ///< blocks whose masks changed, by revision
  std::vector<BlockIndex> free_;
  /// How many of free_'s first entries are in descending order (orderFreeSlots sorts only
  /// those after them and merges: a paging round frees tens of thousands of slots beside a
  /// free list hundreds of thousands long, sorted by the round before).
  size_t free_sorted_ = 0;
  /// Per memory page of the arena: handed back by releaseFreePages() and not used since.
  std::vector<uint8_t> page_released_;
  BlockKeyTable index_;
  std::unordered_map<BlockKey, std::vector<BlockIndex>, SuperKeyHash> super_;
};

}  // namespace fragg
