// BlockMap: creation and lookups, erase and the free list, clear, the coarse spatial index
// (forEachInBox) against brute force, forEach, exact observed bounds, memory accounting, moves,
// and the chunk allocator it is given.
#include "fragg_map/block_map.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <map>
#include <new>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "fragg_map/block_view.h"

namespace fragg {
namespace {

struct KeyLess {
  bool operator()(const BlockKey& a, const BlockKey& b) const {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  }
};

constexpr size_t kChunkBytes = BlockMap::kBlocksPerChunk * sizeof(Block);

/// Counts chunks, checks that every chunk comes back once with its size, and can be told to
/// fail (std::bad_alloc) like a full pinned-memory pool.
class CountingAllocator : public ChunkAllocator {
 public:
  ~CountingAllocator() override { EXPECT_TRUE(live_.empty()) << live_.size() << " chunks leaked"; }
  void* allocate(size_t bytes) override {
    if (fail) throw std::bad_alloc();
    ++allocations;
    void* p = ::operator new(bytes, std::align_val_t(4096));
    live_[p] = bytes;
    return p;
  }
  void deallocate(void* p, size_t bytes) override {
    ++deallocations;
    auto it = live_.find(p);
    EXPECT_NE(it, live_.end()) << "a chunk this allocator did not give";
    if (it == live_.end()) return;
    EXPECT_EQ(it->second, bytes);
    live_.erase(it);
    ::operator delete(p, std::align_val_t(4096));
  }
  const char* name() const override { return "counting"; }

  /// Whether `p` lies inside a live chunk.
  bool owns(const void* p) const {
    for (const auto& [chunk, bytes] : live_) {
      const char* c = static_cast<const char*>(chunk);
      if (p >= c && p < c + bytes) return true;
    }
    return false;
  }
  size_t live() const { return live_.size(); }

  int allocations = 0, deallocations = 0;
  bool fail = false;

 private:
  std::map<void*, size_t> live_;
};

std::vector<BlockIndex> collect(const BlockMap& m) {
  std::vector<BlockIndex> out;
  m.forEach([&](BlockIndex i) { out.push_back(i); });
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<BlockIndex> collectInBox(const BlockMap& m, const BlockKey& lo, const BlockKey& hi) {
  std::vector<BlockIndex> out;
  m.forEachInBox(lo, hi, [&](BlockIndex i) { out.push_back(i); });
  std::sort(out.begin(), out.end());
  return out;
}

void observe(BlockMap& m, const VoxelKey& v, int16_t log_odds_fx = 100) {
  m.block(m.findOrCreate(blockKeyOf(v))).cells[cellIndexOf(v)].log_odds_fx = log_odds_fx;
}

TEST(BlockMapTest, FindOrCreateReportsCreationAndInitialisesCells) {
  BlockMap m;
  EXPECT_TRUE(m.empty());
  const BlockKey k{-3, 5, 0};
  bool created = false;
  const BlockIndex i = m.findOrCreate(k, &created);
  EXPECT_TRUE(created);
  EXPECT_EQ(m.size(), 1u);
  EXPECT_FALSE(m.empty());
  EXPECT_EQ(m.meta(i).key, k);
  EXPECT_EQ(m.meta(i).changed_at, 0u);
  for (const Cell& c : m.block(i).cells) {
    EXPECT_FALSE(c.observed());
    EXPECT_EQ(c.hits, 0);
  }
  m.block(i).cells[17].log_odds_fx = 42;
  m.meta(i).changed_at = 9;
  EXPECT_EQ(m.findOrCreate(k, &created), i);
  EXPECT_FALSE(created);
  EXPECT_EQ(m.block(i).cells[17].log_odds_fx, 42);  // an existing block is left alone
  EXPECT_EQ(m.meta(i).changed_at, 9u);
  EXPECT_EQ(m.findOrCreate(k), i);  // no flag wanted
  EXPECT_EQ(m.size(), 1u);
}

TEST(BlockMapTest, FindOrCreateWithoutInitialiseLeavesTheCellsToTheCaller) {
  BlockMap m;
  const BlockIndex a = m.findOrCreate({0, 0, 0});
  for (int c = 0; c < kCellsPerBlock; ++c) m.block(a).cells[c] = Cell{int16_t(c), int16_t(-c)};
  m.meta(a).changed_at = 5;
  m.meta(a).occupied_at = 4;
  m.erase({0, 0, 0});
  // The freed slot comes back: without initialisation its cells are as the last owner left
  // them (the caller overwrites every one); the metadata is always fresh.
  bool created = false;
  const BlockIndex b = m.findOrCreate({7, 7, 7}, &created, false);
  EXPECT_TRUE(created);
  ASSERT_EQ(b, a);
  EXPECT_EQ(m.block(b).cells[300].hits, 300);
  EXPECT_EQ(m.meta(b).key, (BlockKey{7, 7, 7}));
  EXPECT_EQ(m.meta(b).changed_at, 0u);
  EXPECT_EQ(m.meta(b).occupied_at, 0u);
  // With initialisation (the default) a reused slot is all unobserved again.
  m.erase({7, 7, 7});
  const BlockIndex c = m.findOrCreate({8, 8, 8});
  ASSERT_EQ(c, a);
  for (const Cell& cell : m.block(c).cells) {
    EXPECT_FALSE(cell.observed());
    EXPECT_EQ(cell.hits, 0);
  }
}

TEST(BlockMapTest, LookupsOfPresentAndMissingKeys) {
  BlockMap m;
  const VoxelKey v{-1, -9, 16};  // block (-1, -2, 2), cell (7, 7, 0)
  const BlockKey bk = blockKeyOf(v);
  const BlockIndex i = m.findOrCreate(bk);
  m.block(i).cells[cellIndexOf(v)].log_odds_fx = 77;

  EXPECT_EQ(m.find(bk), i);
  EXPECT_EQ(m.findBlock(bk), &m.block(i));
  const BlockMap& cm = m;
  EXPECT_EQ(cm.findBlock(bk), &cm.block(i));
  const Cell* cell = cm.findCell(v);
  ASSERT_NE(cell, nullptr);
  EXPECT_EQ(cell, &m.block(i).cells[7 + 7 * 8]);
  EXPECT_EQ(cell->log_odds_fx, 77);
  EXPECT_FALSE(cm.findCell({-8, -16, 16})->observed());  // same block, another cell

  for (const BlockKey& missing : {BlockKey{1, -2, 2}, BlockKey{-1, -2, -2}, BlockKey{0, 0, 0}}) {
    EXPECT_EQ(m.find(missing), kNoBlock);
    EXPECT_EQ(m.findBlock(missing), nullptr);
    EXPECT_EQ(cm.findBlock(missing), nullptr);
  }
  EXPECT_EQ(cm.findCell({0, -9, 16}), nullptr);  // the block to the +x side
  EXPECT_EQ(cm.findCell({-1, -9, -16}), nullptr);
  EXPECT_EQ(m.size(), 1u);  // lookups create nothing
}

TEST(BlockMapTest, ErasedIndicesAreReusedBeforeTheArenaGrows) {
  auto counting = std::make_shared<CountingAllocator>();
  BlockMap m(counting);
  std::vector<BlockKey> keys;
  for (int i = 0; i < 5; ++i) {
    keys.push_back({i * 100, -i, 3});
    EXPECT_EQ(m.findOrCreate(keys.back()), BlockIndex(i));
  }
  m.erase(keys[1]);
  m.erase(keys[3]);
  m.erase(keys[3]);        // twice: no effect
  m.erase({12345, 0, 0});  // never there: no effect
  EXPECT_EQ(m.size(), 3u);
  EXPECT_EQ(m.find(keys[1]), kNoBlock);
  EXPECT_EQ(m.find(keys[3]), kNoBlock);
  EXPECT_EQ(m.find(keys[4]), 4u);
  EXPECT_EQ(collect(m), (std::vector<BlockIndex>{0, 2, 4}));
  // The erased blocks are gone from the spatial index too.
  EXPECT_EQ(collectInBox(m, {100, -1, 3}, {100, -1, 3}), std::vector<BlockIndex>{});

  const BlockIndex r1 = m.findOrCreate({-50, -50, -50});
  const BlockIndex r2 = m.findOrCreate({-60, -50, -50});
  EXPECT_EQ((std::set<BlockIndex>{r1, r2}), (std::set<BlockIndex>{1, 3}));
  EXPECT_EQ(m.findOrCreate({-70, -50, -50}), 5u);  // free list empty: the next new slot
  EXPECT_EQ(counting->allocations, 1);
  EXPECT_EQ(m.size(), 6u);
  EXPECT_EQ(collect(m), (std::vector<BlockIndex>{0, 1, 2, 3, 4, 5}));
  // The reused slots are found under their new keys only.
  EXPECT_EQ(collectInBox(m, {-60, -50, -50}, {-50, -50, -50}),
            (std::vector<BlockIndex>{std::min(r1, r2), std::max(r1, r2)}));
  EXPECT_EQ(collectInBox(m, {0, -10, 0}, {500, 0, 10}), (std::vector<BlockIndex>{0, 2, 4}));
}

// Rounds as a paging map runs them: blocks erased in no order, the free slots ordered, some
// of them taken again, more erased: after every ordering the next blocks take the lowest free
// slots first, as a whole sort of the free list would hand them out (orderFreeSlots sorts
// only the slots freed since the last ordering and merges them).
TEST(BlockMapTest, RoundsOfErasuresHandOutTheLowestFreeSlotFirst) {
  BlockMap m;
  std::mt19937 rng(11);
  std::vector<BlockKey> live;
  int next = 0;
  auto create = [&] {
    const BlockKey k{next % 97, next / 97, 3};
    ++next;
    m.findOrCreate(k);
    live.push_back(k);
    return k;
  };
  for (int i = 0; i < 3000; ++i) create();
  std::set<BlockIndex> model;  // the free slots
  for (int round = 0; round < 25; ++round) {
    std::shuffle(live.begin(), live.end(), rng);
    const size_t leaving = live.size() / 4;
    std::vector<BlockKey> out(live.end() - static_cast<std::ptrdiff_t>(leaving), live.end());
    live.resize(live.size() - leaving);
    for (const BlockKey& k : out) model.insert(m.find(k));
    if (round % 2 == 0) {
      m.erase(out);
    } else {
      for (const BlockKey& k : out) m.erase(k);
    }
    m.orderFreeSlots();
    ASSERT_EQ(m.freeSlots(), model.size());
    // Some of the free slots are taken again (fewer than were freed, so the list keeps an
    // ordered head and the next round's slots join it), lowest first.
    const size_t taken = leaving / 2 + static_cast<size_t>(round);
    for (size_t j = 0; j < taken && !model.empty(); ++j) {
      const BlockKey k = create();
      ASSERT_EQ(m.find(k), *model.begin()) << "round " << round << ", block " << j;
      model.erase(model.begin());
    }
  }
}

TEST(BlockMapTest, OrderedFreeSlotsAreTakenLowestFirst) {
  BlockMap m;
  std::vector<BlockKey> keys;
  for (int i = 0; i < 64; ++i) {
    keys.push_back({i, 7, -i});
    ASSERT_EQ(m.findOrCreate(keys.back()), BlockIndex(i));
  }
  // Erased in a shuffled order, as a paging round's victims leave.
  std::vector<int> gone;
  for (int i = 0; i < 64; i += 3) gone.push_back(i);
  std::mt19937 rng(5);
  std::shuffle(gone.begin(), gone.end(), rng);
  for (int i : gone) m.erase(keys[static_cast<size_t>(i)]);
  m.orderFreeSlots();
  EXPECT_EQ(m.freeSlots(), gone.size());
  std::sort(gone.begin(), gone.end());
  for (size_t j = 0; j < gone.size(); ++j) {
    const BlockKey k{1000 + static_cast<int>(j), 0, 0};
    EXPECT_EQ(m.findOrCreate(k), BlockIndex(gone[j])) << "new block " << j;
    EXPECT_EQ(m.find(k), BlockIndex(gone[j]));
  }
  EXPECT_EQ(m.freeSlots(), 0u);
  EXPECT_EQ(m.findOrCreate({-1, -1, -1}), 64u);  // then the arena grows
  EXPECT_EQ(m.size(), 65u);
  for (int i = 0; i < 64; ++i) {  // the blocks that stayed kept their slots
    if (i % 3 != 0) {
      EXPECT_EQ(m.find(keys[static_cast<size_t>(i)]), BlockIndex(i));
    }
  }
}

TEST(BlockMapTest, ErasingManyAtOnceEqualsErasingOneByOne) {
  BlockMap batch, single;
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> coord(-40, 40);  // many blocks share coarse-index lists
  std::vector<BlockKey> keys;
  std::set<BlockKey, KeyLess> seen;
  while (keys.size() < 3000) {
    const BlockKey k{coord(rng), coord(rng), coord(rng) / 8};
    if (!seen.insert(k).second) continue;
    keys.push_back(k);
    ASSERT_EQ(batch.findOrCreate(k), single.findOrCreate(k));
  }
  std::vector<BlockKey> gone;
  for (const BlockKey& k : keys)
    if (rng() % 3 == 0) gone.push_back(k);
  gone.push_back({1000, 1000, 1000});  // not in the map: skipped
  gone.push_back(gone.front());        // twice: erased once
  batch.erase(gone);
  for (const BlockKey& k : gone) single.erase(k);
  EXPECT_EQ(batch.size(), single.size());
  EXPECT_EQ(batch.freeSlots(), single.freeSlots());
  EXPECT_EQ(batch.freeSlots(), gone.size() - 2);
  for (const BlockKey& k : keys) EXPECT_EQ(batch.find(k), single.find(k));
  EXPECT_EQ(collect(batch), collect(single));
  // The coarse index lost exactly the erased blocks: boxes of every size agree.
  for (int trial = 0; trial < 200; ++trial) {
    BlockKey lo{coord(rng), coord(rng), coord(rng) / 8}, hi{coord(rng), coord(rng), coord(rng) / 8};
    if (lo.x > hi.x) std::swap(lo.x, hi.x);
    if (lo.y > hi.y) std::swap(lo.y, hi.y);
    if (lo.z > hi.z) std::swap(lo.z, hi.z);
    ASSERT_EQ(collectInBox(batch, lo, hi), collectInBox(single, lo, hi)) << "trial " << trial;
  }
  EXPECT_EQ(collectInBox(batch, {-64, -64, -64}, {64, 64, 64}), collect(single));
}

TEST(BlockMapTest, ClearEmptiesTheMapAndKeepsTheArena) {
  auto counting = std::make_shared<CountingAllocator>();
  BlockMap m(counting);
  std::vector<BlockKey> keys;
  for (int i = 0; i < 1500; ++i) {
    keys.push_back({i % 37 - 18, i / 37 - 20, i % 5});
    observe(m, {keys.back().x * 8, keys.back().y * 8, keys.back().z * 8});
  }
  ASSERT_EQ(m.size(), 1500u);
  EXPECT_EQ(counting->allocations, 2);
  m.clear();
  EXPECT_TRUE(m.empty());
  EXPECT_EQ(m.size(), 0u);
  for (const BlockKey& k : keys) EXPECT_EQ(m.find(k), kNoBlock);
  EXPECT_TRUE(collect(m).empty());
  EXPECT_TRUE(collectInBox(m, {-100, -100, -100}, {100, 100, 100}).empty());
  EXPECT_TRUE(m.observedBounds().empty);
  // Refilling reuses the chunks (starting from slot 0) and gives fresh blocks.
  std::set<BlockIndex> indices;
  for (int i = 0; i < 1500; ++i) indices.insert(m.findOrCreate({i, 0, 0}));
  EXPECT_EQ(indices.size(), 1500u);
  EXPECT_EQ(*indices.begin(), 0u);
  EXPECT_EQ(*indices.rbegin(), 1499u);
  EXPECT_EQ(counting->allocations, 2);
  EXPECT_TRUE(m.observedBounds().empty);
}

TEST(BlockMapTest, ForEachInBoxMatchesBruteForce) {
  std::mt19937 rng(5);
  // Keys around the origin (super-cells of 8^3 blocks on both sides of zero) and a few far
  // ones at the ends of the block-key range.
  std::uniform_int_distribution<int32_t> near(-40, 40);
  constexpr int32_t kMaxBlock = (1 << 28) - 1, kMinBlock = -(1 << 28);
  BlockMap m;
  std::map<BlockKey, BlockIndex, KeyLess> live;
  for (int i = 0; i < 3000; ++i) {
    const BlockKey k{near(rng), near(rng), near(rng)};
    live[k] = m.findOrCreate(k);
  }
  for (const BlockKey& k :
       {BlockKey{kMaxBlock, kMaxBlock, kMaxBlock}, BlockKey{kMinBlock, kMinBlock, kMinBlock},
        BlockKey{kMinBlock, 0, kMaxBlock}, BlockKey{1000000, -1000000, 7}})
    live[k] = m.findOrCreate(k);
  // Erase a third: the index must forget them.
  for (auto it = live.begin(); it != live.end();) {
    if (rng() % 3 == 0) {
      m.erase(it->first);
      it = live.erase(it);
    } else {
      ++it;
    }
  }
  ASSERT_EQ(m.size(), live.size());

  auto brute = [&](const BlockKey& lo, const BlockKey& hi) {
    std::vector<BlockIndex> out;
    for (const auto& [k, i] : live)
      if (k.x >= lo.x && k.x <= hi.x && k.y >= lo.y && k.y <= hi.y && k.z >= lo.z && k.z <= hi.z)
        out.push_back(i);
    std::sort(out.begin(), out.end());
    return out;
  };
  auto check = [&](const BlockKey& lo, const BlockKey& hi) {
    const std::vector<BlockIndex> got = collectInBox(m, lo, hi);  // sorted, duplicates kept
    EXPECT_EQ(got, brute(lo, hi)) << "box " << lo.x << " " << lo.y << " " << lo.z << " .. " << hi.x
                                  << " " << hi.y << " " << hi.z;
  };
  // Random boxes from one block to the whole cloud: small ones walk the box's super-cells,
  // large ones the occupied super-cells.
  std::uniform_int_distribution<int32_t> corner(-48, 48), extent(0, 30);
  for (int i = 0; i < 400; ++i) {
    const BlockKey lo{corner(rng), corner(rng), corner(rng)};
    if (i % 4 == 0) {
      check(lo, {lo.x + extent(rng) * 3, lo.y + extent(rng) * 3, lo.z + extent(rng) * 3});
    } else {
      check(lo, {lo.x + extent(rng) / 4, lo.y + extent(rng) / 4, lo.z + extent(rng) / 4});
    }
  }
  // Boxes on super-cell borders, across zero, single blocks, the whole key range.
  check({-8, -8, -8}, {-1, -1, -1});
  check({-9, -9, -9}, {0, 0, 0});
  check({-1, -1, -1}, {0, 0, 0});
  check({7, 7, 7}, {8, 8, 8});
  check({-40, -40, -40}, {40, 40, 40});
  check({kMinBlock, kMinBlock, kMinBlock}, {kMaxBlock, kMaxBlock, kMaxBlock});
  check({kMaxBlock - 9, kMaxBlock - 9, kMaxBlock - 9}, {kMaxBlock, kMaxBlock, kMaxBlock});
  check({kMinBlock, kMinBlock, kMinBlock}, {kMinBlock + 8, kMinBlock + 8, kMinBlock + 8});
  for (const auto& [k, i] : live) {
    if (rng() % 50 != 0) continue;
    EXPECT_EQ(collectInBox(m, k, k), std::vector<BlockIndex>{i});
  }
  // An inverted box holds nothing.
  EXPECT_TRUE(collectInBox(m, {5, 5, 5}, {4, 40, 40}).empty());
  EXPECT_TRUE(collectInBox(m, {-40, 5, -40}, {40, 4, 40}).empty());
  EXPECT_TRUE(collectInBox(m, {-40, -40, 5}, {40, 40, 4}).empty());
  EXPECT_TRUE(collectInBox(BlockMap(), {-40, -40, -40}, {40, 40, 40}).empty());
}

TEST(BlockMapTest, ForEachVisitsEachLiveBlockOnce) {
  BlockMap m;
  std::set<BlockIndex> live;
  for (int i = 0; i < 200; ++i) live.insert(m.findOrCreate({i, -i, i % 3}));
  for (int i = 0; i < 200; i += 7) {
    live.erase(m.find({i, -i, i % 3}));
    m.erase({i, -i, i % 3});
  }
  const std::vector<BlockIndex> seen = collect(m);  // sorted, duplicates kept
  EXPECT_EQ(seen, std::vector<BlockIndex>(live.begin(), live.end()));
  EXPECT_EQ(seen.size(), m.size());
  int calls = 0;
  BlockMap().forEach([&](BlockIndex) { ++calls; });
  EXPECT_EQ(calls, 0);
}

TEST(BlockMapTest, ForEachCoarseCellGroupsEveryLiveBlockOnceByCell) {
  BlockMap m;
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> coord(-30, 30);  // negative keys: cells by arithmetic shift
  std::set<BlockIndex> live;
  std::vector<BlockKey> keys;
  while (keys.size() < 2000) {
    const BlockKey k{coord(rng), coord(rng), coord(rng) / 4};
    bool created = false;
    const BlockIndex i = m.findOrCreate(k, &created);
    if (!created) continue;
    keys.push_back(k);
    live.insert(i);
  }
  std::vector<BlockKey> gone;
  for (size_t j = 0; j < keys.size(); ++j) {
    if (j % 5 == 0) gone.push_back(keys[j]);
    if (j % 11 == 0) {  // one by one too
      live.erase(m.find(keys[j]));
      m.erase(keys[j]);
    }
  }
  for (const BlockKey& k : gone) live.erase(m.find(k));
  m.erase(gone);
  const auto cellOf = [](const BlockKey& b) {
    return BlockKey{b.x >> kBlockBits, b.y >> kBlockBits, b.z >> kBlockBits};
  };
  std::set<BlockKey, KeyLess> cells;
  std::vector<BlockIndex> seen;
  m.forEachCoarseCell([&](const std::vector<BlockIndex>& cell) {
    ASSERT_FALSE(cell.empty());
    const BlockKey c = cellOf(m.meta(cell.front()).key);
    EXPECT_TRUE(cells.insert(c).second) << "a cell visited twice";
    for (const BlockIndex i : cell) {
      EXPECT_TRUE(m.liveAt(i));
      EXPECT_EQ(cellOf(m.meta(i).key), c);
      seen.push_back(i);
    }
  });
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(seen, std::vector<BlockIndex>(live.begin(), live.end()));
  int calls = 0;
  BlockMap().forEachCoarseCell([&](const std::vector<BlockIndex>&) { ++calls; });
  EXPECT_EQ(calls, 0);
}

TEST(BlockMapTest, ObservedBoundsAreExact) {
  BlockMap m;
  EXPECT_TRUE(m.observedBounds().empty);
  m.findOrCreate({0, 0, 0});
  m.findOrCreate({-5, 3, 2});
  EXPECT_TRUE(m.observedBounds().empty);  // blocks without an observed cell
  // Hits alone do not make a cell observed.
  m.block(m.find({0, 0, 0})).cells[5].hits = 3;
  EXPECT_TRUE(m.observedBounds().empty);

  observe(m, {-40, 24, 16});  // first cell (index 0) of block (-5, 3, 2)
  KeyBounds b = m.observedBounds();
  ASSERT_FALSE(b.empty);
  EXPECT_EQ(b.min, (VoxelKey{-40, 24, 16}));
  EXPECT_EQ(b.max, (VoxelKey{-40, 24, 16}));

  observe(m, {-1, -1, -1});  // last cell (index 511) of block (-1, -1, -1)
  observe(m, {7, 0, 23});    // x at the end of block 0, z at the end of block 2
  observe(m, {-100, -100, -100}, kUnobservedLogOdds);  // a block, but nothing observed
  b = m.observedBounds();
  EXPECT_EQ(b.min, (VoxelKey{-40, -1, -1}));
  EXPECT_EQ(b.max, (VoxelKey{7, 24, 23}));

  // Forgetting the extreme cell shrinks the bounds to the next one.
  m.block(m.find({-5, 3, 2})).cells[0].log_odds_fx = kUnobservedLogOdds;
  b = m.observedBounds();
  EXPECT_EQ(b.min, (VoxelKey{-1, -1, -1}));
  EXPECT_EQ(b.max, (VoxelKey{7, 0, 23}));

  // Random cells, against the brute-force bounds.
  std::mt19937 rng(9);
  std::uniform_int_distribution<int32_t> coord(-300, 300);
  BlockMap r;
  VoxelKey lo{INT32_MAX, INT32_MAX, INT32_MAX}, hi{INT32_MIN, INT32_MIN, INT32_MIN};
  for (int i = 0; i < 500; ++i) {
    const VoxelKey v{coord(rng), coord(rng), coord(rng) - 1000};
    observe(r, v);
    lo = {std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z)};
    hi = {std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z)};
  }
  b = r.observedBounds();
  ASSERT_FALSE(b.empty);
  EXPECT_EQ(b.min, lo);
  EXPECT_EQ(b.max, hi);
}

TEST(BlockMapTest, HostBytesGrowWithBlocks) {
  BlockMap m;
  size_t last = m.hostBytes();
  for (int i = 0; i < 1100; ++i) {
    m.findOrCreate({i, 2 * i, -i});
    const size_t now = m.hostBytes();
    // Capacities (metadata, index slots) grow in steps: never down.
    EXPECT_GE(now, last) << "block " << i;
    last = now;
    if (i == 0) {
      EXPECT_GE(now, kChunkBytes);
    }
  }
  // Two chunks of cells, a record and at least two index slots (16 bytes) per block.
  EXPECT_GE(last, 2 * kChunkBytes + 1100 * (sizeof(BlockMeta) + 32));
}

TEST(BlockMapTest, MovesKeepTheContents) {
  auto counting = std::make_shared<CountingAllocator>();
  {
    BlockMap a(counting);
    for (int i = 0; i < 1030; ++i) observe(a, {8 * i, -8 * i, i}, int16_t(i));
    const Block* first = &a.block(a.find({0, 0, 0}));

    BlockMap b(std::move(a));
    ASSERT_EQ(b.size(), 1030u);
    EXPECT_EQ(&b.block(b.find({0, 0, 0})), first);  // the arena moved, not copied
    for (int i = 0; i < 1030; i += 97) {
      const Cell* c = b.findCell({8 * i, -8 * i, i});
      ASSERT_NE(c, nullptr);
      EXPECT_EQ(c->log_odds_fx, i);
    }
    EXPECT_EQ(collectInBox(b, {-1, -1, 0}, {1, 1, 0}).size(), 2u);  // i = 0, 1
    EXPECT_EQ(counting->allocations, 2);
    // The moved-from map is empty and still usable.
    EXPECT_TRUE(a.empty());
    EXPECT_EQ(a.find({0, 0, 0}), kNoBlock);
    EXPECT_TRUE(collect(a).empty());
    EXPECT_TRUE(a.observedBounds().empty);
    observe(a, {1, 2, 3});
    EXPECT_EQ(a.size(), 1u);
    EXPECT_EQ(counting->allocations, 3);

    // Assignment gives the target's old chunks back to its allocator.
    auto other = std::make_shared<CountingAllocator>();
    BlockMap c(other);
    observe(c, {100, 100, 100});
    c = std::move(b);
    EXPECT_EQ(other->live(), 0u);
    EXPECT_EQ(c.size(), 1030u);
    EXPECT_EQ(c.find({100 >> 3, 100 >> 3, 100 >> 3}), kNoBlock);
    EXPECT_EQ(c.findCell({8 * 1029, -8 * 1029, 1029})->log_odds_fx, 1029);
    EXPECT_EQ(c.observedBounds().max.x, 8 * 1029);
    EXPECT_TRUE(b.empty());
    BlockMap& same = c;
    c = std::move(same);  // self-move keeps everything
    EXPECT_EQ(c.size(), 1030u);
  }
  EXPECT_EQ(counting->live(), 0u);  // every chunk back, to the allocator that gave it
  EXPECT_EQ(counting->deallocations, 3);
}

TEST(BlockMapTest, ChunksComeFromTheGivenAllocatorAndStayPut) {
  auto counting = std::make_shared<CountingAllocator>();
  {
    BlockMap m(counting);
    EXPECT_EQ(counting->allocations, 0);  // nothing before the first block
    const BlockIndex first = m.findOrCreate({0, 0, 0});
    EXPECT_EQ(counting->allocations, 1);
    const Block* first_address = &m.block(first);
    for (int i = 1; i < 2 * int(BlockMap::kBlocksPerChunk) + 1; ++i) {
      const BlockIndex b = m.findOrCreate({i, 0, 0});
      EXPECT_TRUE(counting->owns(&m.block(b))) << i;
      EXPECT_TRUE(counting->owns(&m.block(b).cells[kCellsPerBlock - 1])) << i;
    }
    EXPECT_EQ(counting->allocations, 3);
    EXPECT_EQ(&m.block(first), first_address);  // stable while the map grows
    EXPECT_EQ(counting->deallocations, 0);
  }
  EXPECT_EQ(counting->deallocations, 3);
  EXPECT_EQ(counting->live(), 0u);
}

TEST(BlockMapTest, AFailedChunkAllocationLeavesTheMapAsItWas) {
  auto counting = std::make_shared<CountingAllocator>();
  BlockMap m(counting);
  for (int i = 0; i < int(BlockMap::kBlocksPerChunk); ++i) m.findOrCreate({i, 0, 0});
  counting->fail = true;
  bool created = true;
  EXPECT_THROW(m.findOrCreate({-1, 0, 0}, &created), std::bad_alloc);
  EXPECT_EQ(m.size(), BlockMap::kBlocksPerChunk);
  EXPECT_EQ(m.find({-1, 0, 0}), kNoBlock);
  EXPECT_TRUE(collectInBox(m, {-1, 0, 0}, {-1, 0, 0}).empty());
  // A freed slot needs no chunk; once memory is back the map grows as before.
  m.erase({5, 0, 0});
  EXPECT_EQ(m.findOrCreate({-1, 0, 0}), 5u);
  counting->fail = false;
  EXPECT_EQ(m.findOrCreate({-2, 0, 0}), BlockIndex(BlockMap::kBlocksPerChunk));
  EXPECT_EQ(m.size(), BlockMap::kBlocksPerChunk + 1);
}

}  // namespace
}  // namespace fragg

namespace fragg {
namespace {

// BlockView's slots: a walk over the stamps in slot order lists what the keyed walk lists,
// ascending; an erased slot holds no key and no stamps (never listed, holds() false for its old
// key) until another block takes it; erasing many at once and clear() do the same.
TEST(BlockViewSlots, ChangedSlotsEqualTheChangedKeysAndErasedSlotsHoldNothing) {
  BlockMap blocks;
  std::vector<BlockKey> keys;
  for (int i = 0; i < 40; ++i) keys.push_back({i % 7 - 3, i / 7, i % 3});
  for (size_t j = 0; j < keys.size(); ++j) {
    BlockMeta& m = blocks.meta(blocks.findOrCreate(keys[j]));
    m.changed_at = m.state_at = j + 1;  // block j changed at revision j + 1
  }
  const BlockView view(blocks);
  const auto expectListing = [&](uint64_t revision, const std::string& when) {
    SCOPED_TRACE(when);
    const std::vector<BlockIndex> slots = view.changedSlotsSince(revision, BlockChange::kState);
    EXPECT_TRUE(std::is_sorted(slots.begin(), slots.end()));
    std::set<BlockKey, KeyLess> from_slots, from_keys;
    for (const BlockIndex s : slots) {
      ASSERT_LT(s, view.slotCount());
      EXPECT_TRUE(view.holds(s, view.keyAt(s)));
      EXPECT_EQ(view.slotOf(view.keyAt(s)), s);
      EXPECT_EQ(&view.blockAt(s), view.findBlock(view.keyAt(s)));
      EXPECT_EQ(&view.masksAt(s), view.findMasks(view.keyAt(s)));
      from_slots.insert(view.keyAt(s));
    }
    for (const BlockKey& k : view.changedSince(revision, BlockChange::kState)) from_keys.insert(k);
    EXPECT_EQ(slots.size(), from_slots.size());
    EXPECT_EQ(from_slots, from_keys);
  };
  expectListing(0, "all");
  expectListing(25, "the last 15");
  const BlockIndex gone = blocks.find(keys[30]);
  blocks.erase(keys[30]);
  EXPECT_FALSE(blocks.liveAt(gone));
  EXPECT_FALSE(view.holds(gone, keys[30]));
  EXPECT_EQ(view.keyAt(gone), BlockMap::kFreedSlotKey);
  expectListing(25, "one erased");
  EXPECT_EQ(view.changedSlotsSince(25, BlockChange::kState).size(), 14u);
  const std::map<BlockIndex, BlockKey> freed = {
      {gone, keys[30]}, {blocks.find(keys[31]), keys[31]}, {blocks.find(keys[32]), keys[32]}};
  blocks.erase(std::vector<BlockKey>{keys[31], keys[32], BlockKey{99, 99, 99}});
  EXPECT_EQ(view.changedSlotsSince(25, BlockChange::kState).size(), 12u);
  EXPECT_EQ(view.allSlots().size(), blocks.size());
  // Another block takes a freed slot: the slot holds it, not the old key.
  const BlockIndex taken = blocks.findOrCreate({50, 50, 50});
  ASSERT_EQ(freed.count(taken), 1u) << "a freed slot is taken before the arena grows";
  EXPECT_TRUE(view.holds(taken, {50, 50, 50}));
  EXPECT_FALSE(view.holds(taken, freed.at(taken)));
  blocks.clear();
  EXPECT_TRUE(view.allSlots().empty());
  EXPECT_TRUE(view.changedSlotsSince(0, BlockChange::kAny).empty());
}

// A walk over a large map's stamps runs on the map's threads in ranges (kParallelWalkSlots):
// it lists exactly the slots a one-thread walk lists, ascending, for every stamp, with erased
// slots among them, whatever the thread count (3: ranges of unequal ends).
TEST(BlockViewSlots, ALargeMapsWalkOnSeveralThreadsListsWhatOneThreadLists) {
  BlockMap blocks;
  uint64_t state = 12345;
  const auto next = [&] {  // a fixed LCG: the same stamps on every run
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return state >> 33;
  };
  constexpr int kBlocks = 40000;  // above the walk's threshold for threads
  std::vector<BlockKey> keys;
  for (int i = 0; i < kBlocks; ++i) {
    const BlockKey k{i % 53 - 26, (i / 53) % 41 - 20, i / (53 * 41)};
    keys.push_back(k);
    BlockMeta& m = blocks.meta(blocks.findOrCreate(k));
    m.masks_at = next() % 100;
    m.occupied_at = m.masks_at + next() % 10;
    m.state_at = m.occupied_at + next() % 10;
    m.changed_at = m.state_at + next() % 10;
  }
  std::vector<BlockKey> erased;
  for (int i = 0; i < kBlocks; i += 97) erased.push_back(keys[i]);
  blocks.erase(erased);
  const BlockView view(blocks);
  const int threads_before = omp_get_max_threads();
  for (const int threads : {1, 2, 3}) {
    omp_set_num_threads(threads);
    for (const BlockChange what :
         {BlockChange::kAny, BlockChange::kOccupied, BlockChange::kState}) {
      for (const uint64_t revision : {uint64_t{0}, uint64_t{50}, uint64_t{110}, uint64_t{200}}) {
        SCOPED_TRACE(::testing::Message()
                     << threads << " threads, change " << int(what) << ", after " << revision);
        std::vector<BlockIndex> expected;
        for (BlockIndex i = 0; i < view.slotCount(); ++i) {
          if (!blocks.liveAt(i)) continue;
          const BlockStamps st = view.stamps(view.keyAt(i));
          const uint64_t stamp = what == BlockChange::kOccupied ? st.occupied_at
                                 : what == BlockChange::kState  ? st.state_at
                                                                : st.changed_at;
          if (stamp > revision) expected.push_back(i);
        }
        EXPECT_EQ(view.changedSlotsSince(revision, what), expected);
      }
    }
  }
  omp_set_num_threads(threads_before);
}

}  // namespace
}  // namespace fragg
