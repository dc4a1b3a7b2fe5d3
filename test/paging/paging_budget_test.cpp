// The paging budget as a hard limit (CPU backend), and commits that compress only what changed:
// the resident blocks and the records kept for the next commit never exceed the budget, not
// even inside a scan; a scan whose regions alone exceed it is refused with the map intact; a
// commit after one changed cell compresses that cell's block only, and the store still reads
// back to the map.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>

#include "fragg_map/cell_writer.h"
#include "fragg_map/errors.h"
#include "fragg_map/internal/pager.h"
#include "fragg_map/store/page_stores.h"
#include "paging_scenes.h"

namespace fragg::test {
namespace {

constexpr int kScans = 80;

/// Block keys in the stores' order (storeOrder), for sets.
using KeySet = std::set<BlockKey, decltype(&storeOrder)>;

PagingPolicy budgetOf(double mb) {
  PagingPolicy p;
  p.budget_mb = mb;
  p.radius_m = 4.0;
  p.commit_every_scans = 7;
  p.commit_every_s = 0;
  return p;
}

class PagingBudget : public ::testing::TestWithParam<PageStoreKind> {
 protected:
  std::string storePath(const std::string& dir) const {
    return dir + (GetParam() == PageStoreKind::kLmdb ? "/map.lmdb" : "/map.db");
  }
  void SetUp() override {
    if (GetParam() == PageStoreKind::kLmdb && !lmdbAvailable()) GTEST_SKIP() << "no LMDB";
  }
};

/// Makes a block at each key (one occupied cell, changed at revision 1) and commits them.
void makeAndCommit(Pager& pager, BlockMap& blocks, const std::vector<BlockKey>& keys) {
  for (const BlockKey& k : keys) {
    const BlockIndex i = blocks.findOrCreate(k);
    blocks.block(i).cells[0] = Cell{1, 100};
    blocks.meta(i).changed_at = 1;
  }
  StoreMapMeta meta;
  meta.resolution_m = 0.05;
  pager.commit(blocks, 1, meta);
}

void insertScans(Map& map, int from, int to) {
  for (int i = from; i < to; ++i) {
    const Eigen::Isometry3d T = corridorPose(i, kScans);
    map.insert(corridorScan(T), T, corridorSensor());
  }
}

TEST_P(PagingBudget, ResidentBlocksAndKeptRecordsNeverExceedTheBudget) {
  const std::string dir = testDir();
  Map memory(corridorParams());
  insertScans(memory, 0, kScans);
  Map paged(corridorParams());
  // 10 MB: about 4,496 blocks of the corridor's 8,359 (2,332 bytes each: the map's arrays are
  // reserved for the budget, Pager::reservedBlockBytes); one scan reaches up to ~3,900.
  paged.attachPageStore(openPageStore(storePath(dir), false), budgetOf(10.0));
  const PagingStats at_start = paged.pagingStats();
  ASSERT_GT(at_start.budget_blocks, 0u);
  ASSERT_LT(at_start.budget_blocks, memory.blockCount());
  for (int i = 0; i < kScans; ++i) {
    insertScans(paged, i, i + 1);
    // The peak counts every moment the resident blocks grow (a page-in, a scan's new blocks)
    // and every record kept: it is the most the map held, not a sample after the scan.
    const PagingStats st = paged.pagingStats();
    ASSERT_LE(st.peak_resident_blocks, st.budget_blocks) << "scan " << i;
    ASSERT_LE(st.peak_counted_bytes, st.budget_bytes) << "scan " << i;
  }
  const PagingStats st = paged.pagingStats();
  EXPECT_GT(st.pages_evicted, 1000u);
  EXPECT_GT(st.pages_read, 100u);
  // Commits kept the regions' records and compressed the changed blocks only.
  EXPECT_GT(st.record_cache_bytes, 0u);
  EXPECT_LT(st.blocks_encoded, st.pages_written);
  paged.commitPages();
  std::string why;
  const Map from_store = Map::loadPageStore(*openPageStore(storePath(dir), true));
  EXPECT_TRUE(sameBlocks(from_store, memory, &why)) << why;
  paged.ensureAllResident();  // no budget check from here: the whole map comes back
  EXPECT_TRUE(sameBlocks(paged, memory, &why)) << why;
}

TEST_P(PagingBudget, AScanThatCannotFitTheBudgetIsRefusedAndTheMapStaysAsItWas) {
  const std::string dir = testDir();
  Map paged(corridorParams());
  // 0.25 MB: 101 blocks, fewer than one corridor scan reaches.
  paged.attachPageStore(openPageStore(storePath(dir), false), budgetOf(0.25));
  const Eigen::Isometry3d T = corridorPose(0, kScans);
  try {
    paged.insert(corridorScan(T), T, corridorSensor());
    ADD_FAILURE() << "a scan larger than the budget was integrated";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("raise the budget"), std::string::npos) << e.what();
  }
  EXPECT_EQ(paged.scanCount(), 0u);
  EXPECT_EQ(paged.blockCount(), 0u);
  EXPECT_LE(paged.pagingStats().peak_resident_blocks, paged.pagingStats().budget_blocks);

  // A scan that fits goes in afterwards, as it would into a map without paging.
  const PointCloud few = twoPointScan(T);
  paged.insert(few, T, corridorSensor());
  Map memory(corridorParams());
  memory.insert(few, T, corridorSensor());
  EXPECT_EQ(paged.scanCount(), 1u);
  std::string why;
  EXPECT_TRUE(sameBlocks(paged, memory, &why)) << why;
}

TEST_P(PagingBudget, KeptRecordsMakeWayForBlocksInsteadOfPushingThemOut) {
  // 64 blocks (one 4x4x4-block region, each with 64 cells observed) under a budget of 80
  // blocks (79 after rounding); a commit keeps the records that fit beside them. 79 blocks then
  // fit the budget without the records: none has to leave (the records are dropped for them),
  // where counting the records would page blocks out to keep them.
  const std::string dir = testDir();
  constexpr size_t kBlocks = 64, kRoom = 16;
  PagingPolicy policy = budgetOf(0);
  policy.background_writer = false;  // no commit in flight to count: deterministic
  policy.budget_mb =
      static_cast<double>((kBlocks + kRoom) * Pager::reservedBlockBytes()) / 1048576.0;
  BlockMap blocks;
  Pager pager(openPageStore(storePath(dir), false), policy, 0.05);
  EXPECT_GE(pager.reserveSlots(blocks), kBlocks + kRoom - 1);
  ASSERT_EQ(pager.blockBytes(), Pager::reservedBlockBytes());
  for (int32_t j = 0; j < static_cast<int32_t>(kBlocks); ++j) {
    const BlockIndex i = blocks.findOrCreate({j % 4, (j / 4) % 4, j / 16});
    // 64 cells a block with scattered values: the records weigh more than one block.
    for (int c = 0; c < 64; ++c)
      blocks.block(i).cells[(j * 7 + c * 131) % kCellsPerBlock] =
          Cell{static_cast<int16_t>(c % 3), static_cast<int16_t>(-400 + (j * 131 + c * 17) % 800)};
    blocks.meta(i).changed_at = 1;
  }
  StoreMapMeta meta;
  meta.resolution_m = 0.05;
  pager.commit(blocks, 1, meta);
  PagingStats st = pager.stats(blocks);
  ASSERT_GT(st.record_cache_bytes, 0u);  // the region's record was kept
  const size_t full = (kBlocks + kRoom - 1) * Pager::reservedBlockBytes() + st.record_cache_bytes;
  ASSERT_GT(full, st.budget_bytes) << "the records must not fit beside 79 blocks";
  EXPECT_EQ(pager.excessOverBudget(kBlocks + kRoom - 1), 0u);
  EXPECT_GT(pager.excessOverBudget(kBlocks + kRoom + 1), 0u);  // blocks alone over: excess
  // Room for 79 blocks: the records are dropped until everything counted fits.
  EXPECT_TRUE(pager.dropRecordsToFit(kBlocks + kRoom - 1));
  st = pager.stats(blocks);
  EXPECT_LE((kBlocks + kRoom - 1) * Pager::reservedBlockBytes() + st.record_cache_bytes,
            st.budget_bytes);
  EXPECT_FALSE(pager.dropRecordsToFit(kBlocks + kRoom + 1));
}

TEST_P(PagingBudget, PagedOutRegionsInABoxAndTheRoomLeftForNewBlocks) {
  // What the CUDA backend asks the pager before each ray pass (DevicePaging): the regions with a
  // paged-out block that meet the scan's window (their blocks are missed, not created), and how
  // many blocks the rays may still create.
  const std::string dir = testDir();
  PagingPolicy policy = budgetOf(0);
  policy.background_writer = false;  // no commit in flight to count: deterministic
  policy.budget_mb = static_cast<double>(200 * Pager::reservedBlockBytes()) / 1048576.0;
  BlockMap blocks;
  Pager pager(openPageStore(storePath(dir), false), policy, 0.05);
  pager.reserveSlots(blocks);
  const size_t budget = pager.stats(blocks).budget_blocks;
  ASSERT_GE(budget, 199u);
  EXPECT_EQ(pager.roomFor(0), budget);
  EXPECT_EQ(pager.roomFor(budget - 5), 5u);
  EXPECT_EQ(pager.roomFor(budget + 5), 0u);

  // Blocks in region (0,0,0), in region (3,0,0) and in region (-3,-1,-1).
  constexpr int32_t e = 1 << kRegionBits;
  const std::vector<BlockKey> near = {{0, 0, 0}, {1, 0, 0}};
  const std::vector<BlockKey> far = {{3 * e, 0, 0}, {3 * e, 1, 0}};
  const std::vector<BlockKey> below = {{-3 * e, -1, -1}};
  std::vector<BlockKey> all = near;
  all.insert(all.end(), far.begin(), far.end());
  all.insert(all.end(), below.begin(), below.end());
  makeAndCommit(pager, blocks, all);
  EXPECT_TRUE(pager.pagedOutRegionsIn({-8 * e, -8 * e, -8 * e}, {8 * e, 8 * e, 8 * e}).empty());

  // Region (3,0,0) leaves with a change the store lacks (held for the next commit), region
  // (-3,-1,-1) clean.
  blocks.block(blocks.find(far[1])).cells[1] = Cell{1, 200};
  blocks.meta(blocks.find(far[1])).changed_at = 2;
  std::vector<BlockIndex> out;
  for (const auto* keys : {&far, &below})
    for (const BlockKey& k : *keys) out.push_back(blocks.find(k));
  pager.pageOut(out, blocks);
  ASSERT_EQ(blocks.size(), near.size());
  ASSERT_GT(pager.heldBytes(), 0u);

  const BlockKey r3{3, 0, 0}, rm{-3, -1, -1};
  // A box that meets region 3 at one block where none was paged out still names it (the
  // region comes back whole); the regions in store order (z, y, x).
  const BlockKey corner{3 * e + e - 1, e - 1, e - 1};
  ASSERT_FALSE(pager.isPagedOut(corner));
  EXPECT_EQ(pager.pagedOutRegionsIn(corner, corner), (std::vector<BlockKey>{r3}));
  EXPECT_EQ(pager.pagedOutRegionsIn({-4 * e, -4 * e, -4 * e}, {4 * e, 4 * e, 4 * e}),
            (std::vector<BlockKey>{rm, r3}));
  EXPECT_TRUE(pager.pagedOutRegionsIn({0, 0, 0}, {3 * e - 1, e - 1, e - 1}).empty());
  EXPECT_TRUE(pager.pagedOutRegionsIn({-3 * e + e, -e, -e}, {-1, -1, -1}).empty());

  // The held record takes room from new blocks (it stays whatever leaves).
  const size_t budget_bytes = pager.stats(blocks).budget_bytes;
  EXPECT_EQ(pager.roomFor(0), (budget_bytes - pager.heldBytes()) / Pager::reservedBlockBytes());
  EXPECT_LT(pager.roomFor(0), budget);

  // Read back, region 3 is no longer paged out.
  const std::vector<BlockIndex> back = pager.pageIn(std::vector<BlockKey>{far[0]}, blocks);
  EXPECT_EQ(back.size(), far.size());
  EXPECT_EQ(pager.pagedOutRegionsIn({0, 0, 0}, {4 * e, 4 * e, 4 * e}).size(), 0u);
  EXPECT_EQ(pager.pagedOutRegionsIn({-4 * e, -4 * e, -4 * e}, {0, 0, 0}),
            (std::vector<BlockKey>{rm}));
}

// Pager::pagedOutOfRegions (what a scan's keys bring back: every paged-out block of their
// regions; with `fresh`, how many of the keys are neither resident nor paged out) against a
// brute-force answer, over whole regions paged out on both sides of the origin, with key sets
// small (one thread) and large (split over the threads).
TEST_P(PagingBudget, PagedOutOfRegionsEqualsABruteForceAnswer) {
  const std::string dir = testDir();
  PagingPolicy policy = budgetOf(64.0);
  policy.background_writer = false;
  BlockMap blocks;
  Pager pager(openPageStore(storePath(dir), false), policy, 0.05);
  pager.reserveSlots(blocks);
  uint32_t seed = 2024;
  auto next = [&seed](int32_t n) {
    seed = seed * 1664525u + 1013904223u;
    return static_cast<int32_t>((seed >> 8) % static_cast<uint32_t>(n));
  };
  // Blocks scattered over [-24, 24)^3 (regions of 4^3 blocks, super regions of 8^3).
  std::vector<BlockKey> made;
  for (int j = 0; j < 3000; ++j) made.push_back({next(48) - 24, next(48) - 24, next(48) - 24});
  makeAndCommit(pager, blocks, made);
  // Whole regions leave: about one in three.
  KeySet paged(storeOrder);
  std::vector<BlockIndex> out;
  blocks.forEach([&](BlockIndex i) {
    const BlockKey r = regionOf(blocks.meta(i).key);
    if (((r.x * 7 + r.y * 13 + r.z * 29) % 3 + 3) % 3 == 0) {
      out.push_back(i);
      paged.insert(blocks.meta(i).key);
    }
  });
  ASSERT_GT(paged.size(), 300u);
  pager.pageOut(out, blocks);
  for (const BlockKey& k : paged) ASSERT_TRUE(pager.isPagedOut(k));
  for (const size_t n : {size_t{50}, size_t{20000}}) {
    std::vector<BlockKey> keys;
    for (size_t j = 0; j < n; ++j) keys.push_back({next(64) - 32, next(64) - 32, next(64) - 32});
    KeySet regions(storeOrder);
    size_t want_fresh = 0;
    for (const BlockKey& k : keys) {
      want_fresh += !paged.count(k) && blocks.find(k) == kNoBlock;
      for (const BlockKey& p : paged)
        if (regionOf(p) == regionOf(k)) {
          regions.insert(regionOf(k));
          break;
        }
    }
    KeySet want(storeOrder);
    for (const BlockKey& p : paged)
      if (regions.count(regionOf(p))) want.insert(p);
    size_t fresh = 0;
    const std::vector<BlockKey> got = pager.pagedOutOfRegions(keys, blocks, &fresh);
    EXPECT_EQ(fresh, want_fresh) << n << " keys";
    EXPECT_EQ(got.size(), want.size()) << n << " keys";
    EXPECT_EQ(KeySet(got.begin(), got.end(), storeOrder), want) << n << " keys";
    EXPECT_FALSE(want.empty()) << n << " keys: the check is empty";
  }
}

TEST_P(PagingBudget, ACommitCompressesOnlyTheBlocksThatChanged) {
  const std::string dir = testDir();
  Map paged(corridorParams());
  PagingPolicy policy = budgetOf(0);  // no budget: every block stays, each commit explicit
  policy.commit_every_scans = 0;
  paged.attachPageStore(openPageStore(storePath(dir), false), policy);
  insertScans(paged, 0, 10);
  paged.commitPages();
  const PagingStats before = paged.pagingStats();
  ASSERT_GT(paged.blockCount(), 100u);

  // One cell of one block changes: its region's record is written (every block of it), and
  // only that block is compressed again.
  const Eigen::Vector3d p(2.0, 0.0, 1.0);
  const VoxelKey key = paged.keyOf(p);
  paged.writeCells([&](CellWriter& w) { w.set(key, Cell{1, 100}); });
  paged.commitPages();
  const PagingStats after = paged.pagingStats();
  EXPECT_EQ(after.blocks_encoded - before.blocks_encoded, 1u);
  EXPECT_EQ(after.records_written - before.records_written, 1u);
  EXPECT_GE(after.pages_written - before.pages_written, 1u);

  // The record made of kept encodings and the new one reads back to the map.
  const Map from_store = Map::loadPageStore(*openPageStore(storePath(dir), true));
  std::string why;
  EXPECT_TRUE(sameBlocks(from_store, paged, &why)) << why;
}

INSTANTIATE_TEST_SUITE_P(Stores, PagingBudget,
                         ::testing::Values(PageStoreKind::kSqlite, PageStoreKind::kLmdb),
                         [](const auto& info) {
                           return info.param == PageStoreKind::kLmdb ? "Lmdb" : "Sqlite";
                         });

}  // namespace
}  // namespace fragg::test
