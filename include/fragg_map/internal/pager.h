// The map's side of out-of-core paging (Map::attachPageStore): which blocks are in the store
// only, which resident blocks were used least recently, and the commits that keep the store
// equal to the map. The Map calls it around every edit; no block is created over a key that
// is paged out (the Map pages it in first). Blocks page in and out by region (a store record
// holds a region, page_store.h): a region is resident or paged out as a whole, so a commit
// writes a region's record from its resident blocks without reading the store.
#pragma once

#include <Eigen/Core>
#include <bitset>
#include <chrono>
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

#include "fragg_map/block_map.h"
#include "fragg_map/internal/page_writer.h"
#include "fragg_map/map_params.h"
#include "fragg_map/page_store.h"

namespace fragg {

/// The metadata record of a store: what makes it a map on its own.
struct StoreMapMeta {
  double resolution_m = 0;
  OccupancyParams occupancy;
  uint64_t scans = 0;  ///< scans integrated into the committed blocks
};
std::vector<uint8_t> encodeStoreMeta(const StoreMapMeta& meta);
/// IoError naming `where` when the record is not a fragg_map store's metadata.
StoreMapMeta decodeStoreMeta(const std::vector<uint8_t>& bytes, const std::string& where);

class Pager {
 public:
  /// Every committed block of `store` starts paged out. With policy.background_writer the
  /// commits are written by a PageWriter thread.
  Pager(std::shared_ptr<PageStore> store, const PagingPolicy& policy, double resolution_m);
  /// Waits for the commit in flight.
  ~Pager();

  PageStore& store() { return *store_; }
  const PagingPolicy& policy() const { return policy_; }

  /// Whether a block of the regions of [lo, hi] is paged out (no store access).
  [[nodiscard]] bool anyPagedOut(BlockKey lo, BlockKey hi) const;
  bool isPagedOut(const BlockKey& key) const;
  /// Whether the block is paged out with every cell at the lower clamp (it was
  /// BlockMeta::freeSaturated when it left this session; unknown, so false, for the blocks of
  /// a reopened store). Safe on many threads while nothing pages in or out.
  bool isPagedOutSaturated(const BlockKey& key) const;
  size_t pagedOutCount() const { return paged_count_; }
  std::vector<BlockKey> pagedOutKeys() const;
  /// The regions holding a paged-out block that meet [lo, hi], in store order (no store access;
  /// such a region has no resident block).
  [[nodiscard]] std::vector<BlockKey> pagedOutRegionsIn(const BlockKey& lo,
                                                        const BlockKey& hi) const;
  /// Reads the paged-out blocks of the regions of [lo, hi] back into `blocks` (clean: stamped
  /// 0); returns their indices in `blocks`.
  std::vector<BlockIndex> pageIn(BlockKey lo, BlockKey hi, BlockMap& blocks);
  /// The same for the regions of `keys` (whole regions: every block created over one of the
  /// keys finds its region resident).
  std::vector<BlockIndex> pageIn(const std::vector<BlockKey>& keys, BlockMap& blocks);
  /// Every paged-out block.
  std::vector<BlockIndex> pageInAll(BlockMap& blocks);
  /// The paged-out blocks of the regions of `keys` (what pageIn(keys) reads back), and in
  /// *fresh the keys neither resident nor paged out (blocks a scan creates).
  std::vector<BlockKey> pagedOutOfRegions(const std::vector<BlockKey>& keys, const BlockMap& blocks,
                                          size_t* fresh) const;
  /// Reads `wanted` (paged out, no duplicates) back into `blocks`.
  std::vector<BlockIndex> readBack(std::vector<BlockKey> wanted, BlockMap& blocks);
  /// Blocks about to be created (a scan's fresh blocks): the records kept meanwhile leave
  /// room for them. 0 once they exist.
  void reserveBlocks(size_t blocks) { reserved_blocks_ = blocks; }
  /// Drops kept records (regions in key order), then, when they were not enough, waits for the
  /// commit in flight, until `resident` blocks and the records fit the budget; returns whether
  /// the blocks fit (false: the blocks alone exceed it).
  bool dropRecordsToFit(size_t resident);
  /// A paged-out block's cells (from a commit not yet written, else the store); false when
  /// the store has no record of it.
  bool readPagedOut(const BlockKey& key, Block* out);
  /// Blocks of [lo, hi] were used at `stamp` (a scan number): they are paged out last.
  void touch(const BlockKey& lo, const BlockKey& hi, uint64_t stamp);
  /// A resident block was erased (all its cells unknown): its record goes at the next commit.
  void noteErased(const BlockKey& key) { erased_.push_back(key); }
  /// The map was reset: every record goes at the next commit, nothing is paged out.
  void forgetAll(const BlockMap& blocks);
  /// Commit every dirty block (changed after the last commit's revision), not just those.
  void markAllDirty() { all_dirty_ = true; }
  /// The store's last commit holds `scans` scans and equals the map at `revision`.
  void setCommitted(uint64_t scans, uint64_t revision) {
    committed_scans_ = counters_.committed_scans = scans;
    committed_revision_ = revision;
  }

  /// Whether a commit is due: by scans or seconds (the policy), or the records held for it
  /// pass an eighth of the budget.
  bool commitDue(uint64_t scans) const;
  bool overBudget(const BlockMap& blocks) const;
  /// Whether the block changed after the last commit (its record is older than it).
  bool dirty(const BlockMeta& m) const { return all_dirty_ || m.changed_at > committed_revision_; }
  /// Writes the records of the regions with a dirty resident block or an erasure (each region
  /// whole, from its resident blocks) and `meta` in one transaction; `revision`
  /// is the map's revision now (blocks changed after it are dirty next time). The records are
  /// encoded here (the blocks may change or leave as soon as this returns); with the background
  /// writer the transaction runs on its thread (flush() waits for it).
  void commit(const BlockMap& blocks, uint64_t revision, const StoreMapMeta& meta);
  /// Waits until every commit is in the store; IoError when the last one failed.
  void flush();
  /// The resident blocks to page out so that the resident blocks fit the low-water mark, whole
  /// regions: least recently used first, regions within the radius of `sensor_m` last
  /// (farthest first: the budget wins over the radius). With `clean_only`, regions with a
  /// dirty block or an erasure and regions within the radius are left out (they may be fewer
  /// than needed). Deterministic (ties by region key).
  /// `incoming` blocks are about to arrive (they count as resident), and the regions of
  /// `pinned` (block keys) stay: a scan in progress holds them.
  std::vector<BlockIndex> victims(const BlockMap& blocks, const Eigen::Vector3d& sensor_m,
                                  bool clean_only, size_t incoming = 0,
                                  const std::vector<BlockKey>* pinned = nullptr);
  /// The last sensor position victims() or noteSensor() was given.
  const Eigen::Vector3d& lastSensor() const { return last_sensor_m_; }
  void noteSensor(const Eigen::Vector3d& sensor_m) { last_sensor_m_ = sensor_m; }
  /// Blocks the last scan read back or created (CPU backend; 0 for the others).
  size_t lastScanIncoming() const { return last_incoming_; }
  void noteScanIncoming(size_t blocks) { last_incoming_ = blocks; }
  /// RAM the budget counts for one resident block of a host map whose per-block arrays grow
  /// as it grows (by doubling).
  static size_t residentBlockBytes();
  /// RAM the budget counts for one resident block of a host map whose per-block arrays were
  /// sized once for the budget (reserveSlots).
  static size_t reservedBlockBytes();
  /// RAM the budget counts for one resident block of this pager's map: reservedBlockBytes()
  /// after reserveSlots() sized its arrays, else residentBlockBytes().
  [[nodiscard]] size_t blockBytes() const { return block_bytes_; }
  /// Sizes `blocks`' per-block arrays and index once for the block count the budget holds at
  /// reservedBlockBytes() (no-op without a budget), so that they never grow under the budget
  /// and leave nothing behind: a block then counts reservedBlockBytes(). Returns the block
  /// count reserved (0 without a budget). Call it on the map this pager pages, before its
  /// blocks come and go.
  size_t reserveSlots(BlockMap& blocks);
  /// The resident blocks to page out for the budget to hold `resident` blocks, the records
  /// held for the next commit and the commit in flight (0 when within it). Kept records do
  /// not count here: they are dropped to fit (dropRecordsToFit) rather than push blocks out.
  size_t excessOverBudget(size_t resident) const;
  /// The blocks that may join `resident` ones before excessOverBudget() is above 0 (the held
  /// records and the commit in flight beside them; kept records make way); SIZE_MAX without a
  /// budget.
  [[nodiscard]] size_t roomFor(size_t resident) const;
  /// Drops the blocks (whole regions) from RAM; they are paged out. A region with a change
  /// since the last commit leaves as its record, encoded here and held in RAM (counted against
  /// the budget) until the next commit writes it: paging out writes nothing, so the store stays
  /// the map of its last commit and the blocks the sensor still works on are not written.
  void pageOut(const std::vector<BlockIndex>& victims, BlockMap& blocks);
  /// Bytes of the records held for the next commit (changed regions that left).
  size_t heldBytes() const { return held_bytes_; }

  PagingStats stats(const BlockMap& blocks) const;
  /// Resident block count after an edit (for the peak).
  void noteResident(size_t resident);
  /// Time of the map's steps around paging (PagingStats::seconds_sync, seconds_page_out).
  void noteSyncSeconds(double s) { counters_.seconds_sync += s; }
  void notePageOutSeconds(double s) { counters_.seconds_page_out += s; }
  /// The counters the map's paging steps add their times and counts to (rounds, a device
  /// backend's read-ahead and in-scan stops); stats() reports them.
  PagingStats& stageCounters() { return counters_; }

 private:
  using Clock = std::chrono::steady_clock;
  static BlockKey superOf(const BlockKey& b) {
    return {b.x >> kBlockBits, b.y >> kBlockBits, b.z >> kBlockBits};
  }
  void addPagedOut(const BlockKey& key);
  void removePagedOut(const BlockKey& key);
  size_t budgetBlocks() const;
  size_t budgetBytes() const;
  /// RAM of the commit in flight on the background writer: its records and the store's copy
  /// while it writes them (PageStore::commitMemoryBytes); 0 without a writer or a commit.
  size_t writerBytes() const;
  /// What the budget counts with `resident` blocks: their bytes, the records kept and held,
  /// and the commit in flight.
  size_t countedBytes(size_t resident) const;
  /// The resident blocks the budget holds at `fraction` of it beside the held records and the
  /// commit in flight (the kept records make way for blocks).
  size_t blocksWithin(double fraction) const;
  /// Keeps `record` as the region's last, when it fits the budget beside `resident` blocks
  /// (and the reserved ones); else the region has none kept.
  void keepRecord(const BlockKey& region, BlockRecord record, size_t resident);
  void dropRecord(const BlockKey& region);

  std::shared_ptr<PageStore> store_;
  PagingPolicy policy_;
  std::unique_ptr<PageWriter> writer_;  ///< null: commits on the map's thread
  double block_m_;
  /// Paged-out blocks: a bit per block of each 8x8x8-block region that holds one (64 bytes a
  /// region, where a hash set of keys took about 50 bytes a block: the map's paged-out part
  /// is unbounded), so that a box costs its regions, not its blocks.
  using RegionBits = std::bitset<size_t{1} << (3 * kBlockBits)>;
  static size_t bitOf(const BlockKey& b) {
    constexpr int32_t m = (1 << kBlockBits) - 1;
    return static_cast<size_t>((b.x & m) | ((b.y & m) << kBlockBits) |
                               ((b.z & m) << (2 * kBlockBits)));
  }
  static BlockKey keyOfBit(const BlockKey& region, size_t bit) {
    // A region is to its blocks what a block is to its cells.
    const VoxelKey k = voxelKeyOf(region, static_cast<int>(bit));
    return {k.x, k.y, k.z};
  }
  /// Which of its super region's places the region of block `b` takes (kRegionBits <=
  /// kBlockBits: (1 << (kBlockBits - kRegionBits))^3 places).
  static size_t placeOf(const BlockKey& b) {
    constexpr int32_t bits = kBlockBits - kRegionBits, m = (1 << bits) - 1;
    return static_cast<size_t>(((b.x >> kRegionBits) & m) | (((b.y >> kRegionBits) & m) << bits) |
                               (((b.z >> kRegionBits) & m) << (2 * bits)));
  }
  /// Whether a block of `key`'s region is paged out.
  [[nodiscard]] bool regionHasPagedOut(const BlockKey& key) const;
  template <class Fn>
  void forEachPagedOutIn(const BlockKey& lo, const BlockKey& hi, Fn&& fn) const;
  std::unordered_map<BlockKey, RegionBits, BlockKeyHash> paged_super_;
  /// The paged-out blocks that left saturated (a subset of paged_super_'s bits).
  std::unordered_map<BlockKey, RegionBits, BlockKeyHash> saturated_super_;
  size_t paged_count_ = 0;
  bool radius_yield_warned_ = false;
  /// Last use (scan number) by 8x8x8-block region.
  std::unordered_map<BlockKey, uint64_t, BlockKeyHash> last_used_;
  /// The last record of each resident region (written by a commit or read by a page-in,
  /// byte-equal to the store's or the pending batch's): a commit compresses a region's changed
  /// blocks only and copies the others' encodings from it. Counted against the budget.
  std::unordered_map<BlockKey, BlockRecord, BlockKeyHash> records_;
  size_t record_bytes_ = 0;
  /// Records of the regions that left with changes the store does not have yet: written by the
  /// next commit, read by a page-in before the writer's batches and the store.
  struct Held {
    BlockRecord record;
    size_t blocks = 0;
  };
  std::unordered_map<BlockKey, Held, BlockKeyHash> held_;
  size_t held_bytes_ = 0;
  /// Resident regions read back from held_: their store record is older than their blocks
  /// (clean by stamp), so the next commit writes them.
  std::unordered_map<BlockKey, bool, BlockKeyHash> stale_;
  size_t reserved_blocks_ = 0;
  /// What a resident block counts (kResidentBlockBytes, or kReservedBlockBytes once
  /// reserveSlots() sized the map's arrays).
  size_t block_bytes_;
  size_t last_incoming_ = 0;
  Eigen::Vector3d last_sensor_m_ = Eigen::Vector3d::Zero();
  std::vector<BlockKey> erased_;
  bool all_dirty_ = false;
  uint64_t committed_revision_ = 0;
  uint64_t committed_scans_ = 0;
  Clock::time_point last_commit_ = Clock::now();
  PagingStats counters_;
};

}  // namespace fragg
