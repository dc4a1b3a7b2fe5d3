// MaskMirror: after every sync it holds exactly the map's blocks with their current state masks
// (compared with Map::blockView() block by block); a sync that follows insertions and cell
// edits reads only the changed-block list (no rebuild), stamps exactly the blocks whose masks
// changed (and, for kOccupied, those whose occupied cells changed) and keeps every block's
// slot, and counts the cells free or occupied as they change; a change of the map's view
// (clear_bbx, reset, load) rebuilds it and moves its generation; a sync with nothing new does
// nothing.
#include "fragg_map/ros/mask_mirror.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "map_fixtures.h"

namespace fragg::ros {
namespace {

struct KeyLess {
  bool operator()(const fragg::BlockKey& a, const fragg::BlockKey& b) const {
    return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z < b.z;
  }
};
using MasksByKey = std::map<fragg::BlockKey, fragg::BlockStateMasks, KeyLess>;

bool sameMasks(const fragg::BlockStateMasks& a, const fragg::BlockStateMasks& b) {
  return std::memcmp(&a, &b, sizeof(a)) == 0;
}

/// The mirror holds the map's blocks, each with its masks, and nothing else.
void expectMirrors(const fragg::Map& map, const MaskMirror& mirror, const std::string& step) {
  SCOPED_TRACE(step);
  const fragg::BlockView view = map.blockView();
  EXPECT_EQ(mirror.size(), view.size());
  EXPECT_EQ(mirror.slotCount(), view.size());
  size_t differ = 0;
  uint64_t known = 0;
  for (const fragg::BlockIndex s : view.allSlots()) {
    const fragg::BlockStateMasks* m = mirror.findMasks(view.keyAt(s));
    ASSERT_NE(m, nullptr);
    differ += !sameMasks(*m, view.masksAt(s));
    for (int w = 0; w < fragg::kStateMaskWords; ++w)
      known += __builtin_popcountll(view.masksAt(s).occupied[w] | view.masksAt(s).free[w]);
  }
  EXPECT_EQ(differ, 0u);
  EXPECT_EQ(mirror.knownCells(), known);
  // With OctoMap's model every observed cell is free or occupied: memory()'s count.
  EXPECT_EQ(mirror.knownCells(), map.memory().known_voxels);
  for (const fragg::BlockIndex s : mirror.allSlots()) {
    EXPECT_TRUE(view.findBlock(mirror.keyAt(s)) != nullptr);
    EXPECT_TRUE(mirror.holds(s, mirror.keyAt(s)));
    EXPECT_EQ(mirror.slotOf(mirror.keyAt(s)), s);
  }
  EXPECT_EQ(mirror.revision(), map.revision());
}

/// Each block's masks by key (a snapshot).
MasksByKey masksByKey(const fragg::Map& map) {
  MasksByKey out;
  const fragg::BlockView view = map.blockView();
  for (const fragg::BlockIndex s : view.allSlots()) out[view.keyAt(s)] = view.masksAt(s);
  return out;
}

// The mirror's arrays grow by chunks: what they hold keeps its value and its address across
// growth (no copy), new elements are value-initialised, also after a shrink.
TEST(ChunkedArray, GrowsWithoutMovingWhatItHolds) {
  ChunkedArray<uint64_t, 4> a;  // 16 elements a chunk
  std::vector<const uint64_t*> where;
  for (uint64_t i = 0; i < 100; ++i) {
    a.push_back(i * 7 + 1);
    where.push_back(&a[i]);
  }
  a.resize(1000);
  ASSERT_EQ(a.size(), 1000u);
  for (uint64_t i = 0; i < 100; ++i) {
    EXPECT_EQ(a[i], i * 7 + 1);
    EXPECT_EQ(&a[i], where[i]) << i;
  }
  for (size_t i = 100; i < 1000; ++i) EXPECT_EQ(a[i], 0u) << i;
  a[999] = 5;
  a[40] = 9;
  a.resize(30);  // shrink: what comes back when it grows again is zero
  a.resize(1000);
  EXPECT_EQ(a[29], 29u * 7 + 1);
  EXPECT_EQ(a[40], 0u);
  EXPECT_EQ(a[999], 0u);
  a.clear();
  EXPECT_EQ(a.size(), 0u);
  a.push_back(3);
  EXPECT_EQ(a[0], 3u);
}

TEST(MaskMirror, FollowsInsertionsAndEditsFromTheChangedBlockList) {
  fragg::Map map(test::cpuParams(0.1));
  MaskMirror mirror;
  EXPECT_TRUE(mirror.sync(map).rebuilt);  // the first sync reads the (empty) map
  expectMirrors(map, mirror, "empty");
  const uint64_t first_generation = mirror.generation();
  EXPECT_FALSE(mirror.sync(map).rebuilt);
  EXPECT_EQ(mirror.sync(map).listed, 0u) << "nothing new, yet something was read";

  test::insertWall(map, Eigen::Vector3d::Zero(), 3.0);
  const uint64_t after_wall = map.revision();
  MaskMirror::SyncStats s = mirror.sync(map);
  EXPECT_FALSE(s.rebuilt);
  EXPECT_GT(s.added, 10u);
  expectMirrors(map, mirror, "a wall");
  std::vector<fragg::BlockIndex> changed;
  mirror.changedSlotsSince(0, fragg::BlockChange::kMasks, &changed);
  EXPECT_EQ(changed.size(), mirror.size()) << "every block is new";

  // Keep every block's slot, then change some: the mirror lists exactly those.
  std::map<fragg::BlockKey, fragg::BlockIndex, KeyLess> slots;
  for (const fragg::BlockIndex i : mirror.allSlots()) slots[mirror.keyAt(i)] = i;
  const auto before = masksByKey(map);
  test::insertWall(map, Eigen::Vector3d(0.0, 1.5, 0.3), 3.0);
  const fragg::VoxelKey lone{40, -17, 5};
  test::setCell(map, lone, fragg::CellState::kOccupied);
  s = mirror.sync(map);
  EXPECT_FALSE(s.rebuilt);
  expectMirrors(map, mirror, "a second wall and a lone cell");
  for (const auto& [key, slot] : slots) EXPECT_EQ(mirror.slotOf(key), slot) << "a slot moved";
  const auto after = masksByKey(map);
  std::vector<fragg::BlockKey> want_masks, want_occupied;
  for (const auto& [key, m] : after) {
    const auto was = before.find(key);
    if (was == before.end()) {
      want_masks.push_back(key);
      bool any = false;
      for (const uint64_t w : m.occupied) any |= w != 0;
      if (any) want_occupied.push_back(key);
      continue;
    }
    if (!sameMasks(was->second, m)) want_masks.push_back(key);
    if (std::memcmp(was->second.occupied, m.occupied, sizeof(m.occupied)) != 0)
      want_occupied.push_back(key);
  }
  auto got_masks = mirror.changedSince(after_wall, fragg::BlockChange::kMasks);
  auto got_occupied = mirror.changedSince(after_wall, fragg::BlockChange::kOccupied);
  std::sort(got_masks.begin(), got_masks.end(), KeyLess());
  std::sort(got_occupied.begin(), got_occupied.end(), KeyLess());
  std::sort(want_masks.begin(), want_masks.end(), KeyLess());
  std::sort(want_occupied.begin(), want_occupied.end(), KeyLess());
  EXPECT_EQ(got_masks, want_masks);
  EXPECT_EQ(got_occupied, want_occupied);
  EXPECT_FALSE(got_occupied.empty());
  EXPECT_LT(got_occupied.size(), got_masks.size()) << "free cells changed more blocks";
  const fragg::BlockStateMasks* lone_masks = mirror.findMasks(fragg::blockKeyOf(lone));
  ASSERT_NE(lone_masks, nullptr);
  EXPECT_EQ(lone_masks->state(fragg::cellIndexOf(lone)), fragg::CellState::kOccupied);
  EXPECT_EQ(mirror.generation(), first_generation) << "rebuilt without a reason";

  // The view moves (blocks erased): a rebuild, a new generation.
  const uint64_t epoch = map.viewEpoch();
  map.clearBox(Eigen::Vector3d(2.0, -10.0, -10.0), Eigen::Vector3d(10.0, 10.0, 10.0));
  ASSERT_NE(map.viewEpoch(), epoch) << "no block was erased: the case is not tested";
  EXPECT_TRUE(mirror.sync(map).rebuilt);
  EXPECT_NE(mirror.generation(), first_generation);
  expectMirrors(map, mirror, "clear_bbx");
  EXPECT_FALSE(mirror.contains(fragg::blockKeyOf(map.keyOf(Eigen::Vector3d(3.0, 0.0, 0.0)))));
  test::setCell(map, lone, fragg::CellState::kFree);
  EXPECT_FALSE(mirror.sync(map).rebuilt);
  expectMirrors(map, mirror, "the lone cell freed");
  map.reset();
  EXPECT_TRUE(mirror.sync(map).rebuilt);
  expectMirrors(map, mirror, "reset");
  EXPECT_EQ(mirror.size(), 0u);
}

// A sync listing thousands of blocks (the held ones updated in parallel, the new ones added
// after): the same mirror, stamps and count as block by block.
TEST(MaskMirror, ThousandsOfListedBlocksSyncAsOneByOne) {
  fragg::Map map(test::cpuParams(0.1));
  // One cell in every block of a 24 x 24 x 10 slab (5,760 blocks).
  const auto write = [&](int32_t x_blocks, int shift) {
    map.writeCells([&](fragg::CellWriter& cells) {
      for (int32_t bz = 0; bz < 10; ++bz)
        for (int32_t by = 0; by < 24; ++by)
          for (int32_t bx = 0; bx < x_blocks; ++bx) {
            // Occupied or free (a block whose cells are all unknown is not listed: the
            // mirror holds blocks with a known cell).
            const bool occupied = (bx + by + bz + shift) % 2 == 0;
            fragg::Cell c;
            c.log_odds_fx = occupied ? map.model().max_fx : map.model().min_fx;
            c.hits = occupied ? 1 : 0;
            cells.set({bx * 8 + (by % 8), by * 8 + (bz % 8), bz * 8 + (bx % 8)}, c);
          }
    });
  };
  write(24, 0);
  MaskMirror mirror;
  (void)mirror.sync(map);
  expectMirrors(map, mirror, "the slab");
  const uint64_t generation = mirror.generation();
  const uint64_t after_slab = map.revision();
  std::map<fragg::BlockKey, fragg::BlockIndex, KeyLess> slots;
  for (const fragg::BlockIndex i : mirror.allSlots()) slots[mirror.keyAt(i)] = i;
  const auto before = masksByKey(map);
  // Every held block's cell changes state, and the slab grows by 8 x 24 x 10 blocks.
  write(32, 1);
  const MaskMirror::SyncStats s = mirror.sync(map);
  EXPECT_FALSE(s.rebuilt);
  EXPECT_GT(s.listed, 4096u) << "the parallel update is not exercised";
  EXPECT_EQ(s.added, 8u * 24u * 10u);
  EXPECT_EQ(mirror.generation(), generation);
  expectMirrors(map, mirror, "the slab changed and grown");
  for (const auto& [key, slot] : slots) EXPECT_EQ(mirror.slotOf(key), slot) << "a slot moved";
  std::vector<fragg::BlockKey> want_masks, want_occupied;
  for (const auto& [key, m] : masksByKey(map)) {
    const auto was = before.find(key);
    const fragg::BlockStateMasks empty;
    const fragg::BlockStateMasks& old = was == before.end() ? empty : was->second;
    if (was == before.end() || !sameMasks(old, m)) want_masks.push_back(key);
    if (std::memcmp(old.occupied, m.occupied, sizeof(m.occupied)) != 0)
      want_occupied.push_back(key);
  }
  auto got_masks = mirror.changedSince(after_slab, fragg::BlockChange::kMasks);
  auto got_occupied = mirror.changedSince(after_slab, fragg::BlockChange::kOccupied);
  std::sort(got_masks.begin(), got_masks.end(), KeyLess());
  std::sort(got_occupied.begin(), got_occupied.end(), KeyLess());
  EXPECT_EQ(got_masks, want_masks);
  EXPECT_EQ(got_occupied, want_occupied);
  EXPECT_GT(want_occupied.size(), 1000u);
}

TEST(MaskMirror, InvalidateRebuilds) {
  fragg::Map map(test::cpuParams(0.1));
  test::insertWall(map, Eigen::Vector3d::Zero(), 2.0);
  MaskMirror mirror;
  (void)mirror.sync(map);
  const uint64_t g = mirror.generation();
  mirror.invalidate();
  EXPECT_FALSE(mirror.valid());
  EXPECT_TRUE(mirror.sync(map).rebuilt);
  EXPECT_EQ(mirror.generation(), g + 1);
  expectMirrors(map, mirror, "after invalidate");
}

// acceptLag: a sync leaves the mirror behind by up to that many revisions (its blocks, stamps and
// revision as the last sync left them), and syncs it once the map is further ahead, its view
// moved, or the lag goes back to 0; what was left behind is then stamped and listed.
TEST(MaskMirror, AnAcceptedLagLeavesItBehindUntilTheMapIsFurtherAhead) {
  fragg::Map map(test::cpuParams(0.1));
  MaskMirror mirror;
  test::insertWall(map, Eigen::Vector3d::Zero(), 3.0);
  (void)mirror.sync(map);
  const uint64_t synced_at = map.revision();
  const size_t blocks = mirror.size();
  mirror.acceptLag(1);
  EXPECT_EQ(mirror.acceptedLag(), 1u);
  test::insertWall(map, Eigen::Vector3d(0.0, 4.0, 0.0), 3.0);  // new blocks
  ASSERT_EQ(map.revision(), synced_at + 1);
  EXPECT_EQ(mirror.sync(map).lagged, 1u);
  EXPECT_EQ(mirror.revision(), synced_at);
  EXPECT_EQ(mirror.size(), blocks) << "synced although one revision behind";
  EXPECT_TRUE(mirror.changedSince(synced_at, fragg::BlockChange::kMasks).empty());
  test::insertWall(map, Eigen::Vector3d(0.0, -4.0, 0.0), 3.0);  // two behind: synced
  const MaskMirror::SyncStats& s = mirror.sync(map);
  EXPECT_EQ(s.lagged, 0u);
  EXPECT_GT(s.listed, 0u);
  expectMirrors(map, mirror, "two revisions behind");
  const size_t both_walls = mirror.changedSince(synced_at, fragg::BlockChange::kMasks).size();
  EXPECT_GT(mirror.size(), blocks);
  EXPECT_GE(both_walls, mirror.size() - blocks) << "the blocks left behind were not stamped";
  // One behind, but the view moved (blocks erased): rebuilt at once.
  const uint64_t epoch = map.viewEpoch();
  map.clearBox(Eigen::Vector3d(2.0, -10.0, -10.0), Eigen::Vector3d(10.0, 10.0, 10.0));
  ASSERT_NE(map.viewEpoch(), epoch);
  EXPECT_TRUE(mirror.sync(map).rebuilt);
  expectMirrors(map, mirror, "the view moved");
  // Lag 0 again: every sync catches up.
  test::insertWall(map, Eigen::Vector3d(0.5, 0.0, 0.0), 3.0);
  mirror.acceptLag(0);
  EXPECT_EQ(mirror.sync(map).lagged, 0u);
  expectMirrors(map, mirror, "lag 0");
}

}  // namespace
}  // namespace fragg::ros
