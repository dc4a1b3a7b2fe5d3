// Out-of-core paging (DESIGN §11): the interface of a page store, the embedded database that
// holds a map's blocks while they are out of RAM, and the policy that decides which blocks
// leave. Implementations (SQLite, LMDB) live in fragg_map_store (fragg_map/store/).
//
// A store is a map on its own: one record per region of 4x4x4 blocks (region key -> the
// region's blocks, each compressed on its own so that one can be read without the others) and
// one metadata record (the map's resolution, occupancy model and the number of scans it
// holds), written together in one transaction by commitRecords(). Readers see the last
// committed state. The store's format has a version (kPageStoreFormat); a store of another
// version is refused on open with a one-line message naming the command that converts it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "fragg_map/cell.h"
#include "fragg_map/key.h"

namespace fragg {

/// A record holds the blocks of a region (1 << kRegionBits)^3 blocks: 4x4x4 (docs/benchmarks.md,
/// "Records by region": 8x8x8 regions page in 8 times the blocks for each one a ray reaches).
#ifndef FRAGG_PAGE_REGION_BITS
#define FRAGG_PAGE_REGION_BITS 2  // 3 (8x8x8) only for the measurement: records tell their size
#endif
constexpr int kRegionBits = FRAGG_PAGE_REGION_BITS;
static_assert(kRegionBits >= 1 && kRegionBits <= 3, "a region is 2 to 8 blocks on an edge");
constexpr int kRegionMask = (1 << kRegionBits) - 1;
constexpr int kBlocksPerRegion = 1 << (3 * kRegionBits);
/// The version of the store format this build reads and writes: 1 was one record per block
/// (no version recorded), 2 one record per region.
constexpr uint32_t kPageStoreFormat = 2;

/// The region (a key in region units, kRegionBits coarser than blocks) that holds block `b`.
inline BlockKey regionOf(const BlockKey& b) {
  return {b.x >> kRegionBits, b.y >> kRegionBits, b.z >> kRegionBits};
}
/// The first (lowest) block of region `r`.
inline BlockKey firstBlockOf(const BlockKey& r) {
  return {static_cast<int32_t>(static_cast<uint32_t>(r.x) << kRegionBits),
          static_cast<int32_t>(static_cast<uint32_t>(r.y) << kRegionBits),
          static_cast<int32_t>(static_cast<uint32_t>(r.z) << kRegionBits)};
}

/// A region record: the store's encoding of one region's blocks (each compressed, checked).
using BlockRecord = std::vector<uint8_t>;
/// The blocks of one region, by block key (all in the same region, no key twice).
using RegionBlocks = std::vector<std::pair<BlockKey, const Block*>>;

class PageStore {
 public:
  virtual ~PageStore() = default;
  /// "sqlite" or "lmdb".
  virtual const char* kind() const = 0;
  /// Where the store is (its file).
  virtual const std::string& path() const = 0;
  /// Keys of every committed block (from the region records).
  virtual std::vector<BlockKey> keys() = 0;
  /// Reads one committed block; false when there is no record of it. IoError when the record
  /// does not decode to a block.
  virtual bool read(const BlockKey& key, Block* out) = 0;
  /// The committed metadata record (empty: a new store that holds no map yet).
  virtual std::vector<uint8_t> readMeta() = 0;
  /// Every block and the metadata from one snapshot (one read transaction): fn(key, block)
  /// for each block, then the metadata is returned. IoError when a record does not decode.
  virtual std::vector<uint8_t> readAll(
      const std::function<void(const BlockKey&, const Block&)>& fn) = 0;
  /// Reads the committed blocks `keys` from one snapshot into outs[j] (j-th key), each
  /// region's record fetched once, decoding on every core; found[j] says whether keys[j] has
  /// a record. With `records`, a copy of each region record read goes there (region key,
  /// record), so that a later encode() can keep its blocks' encodings. IoError when a record
  /// does not decode.
  virtual std::vector<bool> readMany(
      const std::vector<BlockKey>& keys, const std::vector<Block*>& outs,
      std::vector<std::pair<BlockKey, BlockRecord>>* records = nullptr) = 0;
  /// The records of `regions` (out[j] holds regions[j]'s blocks and no other), encoded on every
  /// core. A block given without cells (nullptr) keeps its encoding from previous[j] (the
  /// region's earlier record, byte for byte: only changed blocks are compressed again);
  /// IoError when previous[j] is missing or does not hold it. Touches no store state: safe on
  /// any thread, while the store reads or writes.
  virtual std::vector<BlockRecord> encode(
      const std::vector<RegionBlocks>& regions,
      const std::vector<const BlockRecord*>& previous = {}) const = 0;
  /// Decodes block `key` of a record made by encode() (safe on any thread); false when the
  /// record does not hold it. IoError when the record does not decode.
  virtual bool decode(const BlockRecord& record, const BlockKey& key, Block* out) const = 0;
  /// Writes the region records (keyed by region: regionOf), erases the regions' records and
  /// replaces the metadata in one transaction: after a crash the store holds either all of it
  /// or none of it. A record replaces its region's: it holds every block of the region.
  /// Throws IoError (nothing written). May run on another thread than the reads (the map's
  /// background writer): reads see the last finished commit meanwhile.
  virtual void commitRecords(const std::vector<std::pair<BlockKey, BlockRecord>>& puts,
                             const std::vector<BlockKey>& erase_regions,
                             const std::vector<uint8_t>& meta) = 0;
  /// Writes blocks and erases blocks (by block key) in one transaction, on the calling thread:
  /// the committed records of the regions they touch are read, changed and written back.
  virtual void commit(const std::vector<std::pair<BlockKey, const Block*>>& puts,
                      const std::vector<BlockKey>& erases, const std::vector<uint8_t>& meta) = 0;
  /// The store's size on disk (its files).
  virtual uint64_t diskBytes() const = 0;
  /// Drops the store's file pages from this process's resident memory where the store maps
  /// its file (they stay in the system's page cache), once they pass a bound; the map calls
  /// it after paging out.
  virtual void releaseMappedPages() {}
  /// RAM the store takes while it commits records of `record_bytes` bytes in all, besides the
  /// records themselves (what the paging budget counts for a commit in flight); 0 where it is
  /// bounded by a fixed cache.
  [[nodiscard]] virtual size_t commitMemoryBytes(size_t record_bytes) const {
    (void)record_bytes;
    return 0;
  }
};

/// When blocks leave RAM (Map::attachPageStore).
struct PagingPolicy {
  /// Resident blocks' memory (cells, metadata, state masks, index), the resident regions' last
  /// records (kept so that a commit compresses only the blocks that changed), the records held
  /// for the next commit and the commit in flight, above which blocks are paged out; 0: never
  /// page out (the store still receives every commit).
  double budget_mb = 0.0;
  /// Blocks whose centre lies within this distance of the last sensor position are paged
  /// out last (farthest first), only when the others cannot bring the map within the budget:
  /// the budget wins over the radius (a warning says so, once).
  double radius_m = 0.0;
  /// Paging out brings the resident blocks down to this fraction of the budget (hysteresis:
  /// fewer, larger rounds).
  double low_water = 0.75;
  /// A device backend (CUDA): the rays walked on the host before the ray pass to find the
  /// paged-out regions it reaches (Map::pageInAhead), an even sample of a denser scan; 0: every
  /// ray. A region the sample misses costs the pass a stop and a pass redone. Three W4 scans
  /// (~162,000 points, 5 cm, 30 m), one thread of the 2-core machine: every ray 20-31 ms;
  /// 32,768 rays 3.3-4.5 ms, missing 1.2-1.5 % of the regions every ray reaches (16,384:
  /// 1.7-2.3 ms, 2.1-3.3 %; 65,536: 5.5-7.6 ms, 0.5-0.6 %).
  size_t read_ahead_rays = 32768;
  /// Dirty resident blocks are committed every this many scans (0: only by seconds, paging
  /// rounds and close) ...
  uint64_t commit_every_scans = 50;
  /// ... or when this many seconds passed since the last commit (0: never by time).
  double commit_every_s = 10.0;
  /// Commits are written to the store by a background thread while the map goes on (the
  /// records are encoded on the map's thread, a snapshot); false: on the map's thread.
  bool background_writer = true;

  void validate() const;
};

struct PagingStats {
  bool enabled = false;
  std::string store;             ///< "sqlite:/path/map.db"
  uint64_t resident_blocks = 0;  ///< in RAM now
  uint64_t peak_resident_blocks = 0;
  uint64_t budget_blocks = 0;  ///< the RAM budget in resident blocks (0: no budget)
  uint64_t paged_blocks = 0;   ///< in the store only
  uint64_t pages_written = 0;  ///< blocks written (in the region records of commits)
  /// ... of them compressed anew (changed since their region's last record; the others keep
  /// their encoding from it)
  uint64_t blocks_encoded = 0;
  uint64_t records_written = 0;  ///< region records written
  /// The budget in bytes, and the most the budget's count ever reached: resident blocks (cells,
  /// metadata, index) plus the resident regions' last records kept for the next commit.
  uint64_t budget_bytes = 0;
  uint64_t peak_counted_bytes = 0;
  uint64_t record_cache_bytes = 0;  ///< the resident regions' last records, now
  uint64_t pages_read = 0;          ///< block records read back into RAM
  /// ... of them read from a commit not yet written (the background writer's batch)
  uint64_t pages_read_pending = 0;
  uint64_t pages_evicted = 0;  ///< blocks dropped from RAM
  /// ... of them in regions that left changed: held as records until the next commit
  uint64_t blocks_held = 0;
  uint64_t commits = 0;
  uint64_t committed_scans = 0;  ///< scans the store holds (its last commit)
  double seconds_commit = 0;     ///< time in commits on the map's thread
  double seconds_writer = 0;     ///< time the background writer spent writing commits
  double seconds_page_in = 0;    ///< time reading blocks back
  /// time writing a device backend's changes back to the host map before a commit or a
  /// paging round (the CPU backend writes the host map directly: 0)
  double seconds_sync = 0;
  double seconds_page_out = 0;  ///< time choosing the blocks that leave and dropping them
  /// ... of it dropping the leaving blocks' device copies (written back first when changed)
  double seconds_evict = 0;
  /// ... of it encoding the changed regions that leave (records held for the next commit)
  double seconds_encode = 0;
  /// ... of it choosing the blocks that leave (Pager::victims: a pass over every resident
  /// block, by region; also where a round finds too few clean blocks and chooses again)
  double seconds_choose = 0;
  /// Paging rounds (blocks paged out to make room): between scans (after one, for the next:
  /// Map::pageAfterScan; or before a device's ray pass, for its read-ahead), and inside a scan
  /// (the CPU backend's page-in of the blocks its rays mark, a device pass's stop).
  uint64_t rounds_between_scans = 0;
  uint64_t rounds_in_scan = 0;
  /// A device backend (the CUDA one): the scans whose rays reached a paged-out region before
  /// the ray pass (walked on the host, Map::pageInAhead), the blocks read back for them, the
  /// walk's time and the reads' (with the rounds that made room for them).
  uint64_t scans_read_ahead = 0;
  uint64_t blocks_read_ahead = 0;
  double seconds_reach = 0;
  double seconds_read_ahead = 0;
  /// A device backend: the times a scan's pass stopped for paging (a ray reached a paged-out
  /// region the walk missed, or the budget had no room for its new blocks; each costs a pass
  /// redone: InsertStats::passes_redone), the blocks read back then, and the time in those stops
  /// (rounds, read-backs), of it writing the device's changes back (also in seconds_sync).
  uint64_t stops_in_scan = 0;
  uint64_t blocks_read_in_scan = 0;
  double seconds_in_scan = 0;
  double seconds_sync_in_scan = 0;
  uint64_t store_bytes = 0;  ///< on disk
};

}  // namespace fragg
