// Changed-block lists per revision (issue 34 item 2) on the CPU backend: the change log on its
// own, and Map::changedBlocksSince(r, BlockChange::kMasks) against the blocks whose masks differ
// between snapshots taken before and after each scan and each named edit.
#include "fragg_map/change_log.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "fragg_map/map.h"
#include "test_scenes.h"

namespace fragg::test {
namespace {

struct KeyLess {
  bool operator()(const BlockKey& a, const BlockKey& b) const {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  }
};
using KeySet = std::set<BlockKey, KeyLess>;
using MaskSnapshot = std::map<BlockKey, BlockStateMasks, KeyLess>;

KeySet setOf(const std::vector<BlockKey>& keys) { return KeySet(keys.begin(), keys.end()); }

TEST(BlockChangeLogTest, AnswersWhatItHoldsAndNothingOlder) {
  BlockChangeLog log(8);
  for (uint64_t r = 1; r <= 4; ++r) {
    log.record(r, BlockKey{int32_t(r), 0, 0});
    log.record(r, BlockKey{0, 0, 0});  // the same block in every revision
  }
  EXPECT_TRUE(log.reaches(0));
  EXPECT_EQ(setOf(log.keysAfter(0)).size(), 5u);  // each key once
  EXPECT_EQ(setOf(log.keysAfter(2)), (KeySet{{0, 0, 0}, {3, 0, 0}, {4, 0, 0}}));
  EXPECT_TRUE(log.keysAfter(4).empty());
  // Full (8 records): the next one drops the older half, revisions 1 and 2.
  log.record(5, BlockKey{5, 0, 0});
  EXPECT_FALSE(log.reaches(1));
  EXPECT_TRUE(log.reaches(2));
  EXPECT_EQ(setOf(log.keysAfter(2)), (KeySet{{0, 0, 0}, {3, 0, 0}, {4, 0, 0}, {5, 0, 0}}));
  // One revision asked about (the records binary-searched, nothing to deduplicate).
  EXPECT_EQ(log.keysAfter(4), (std::vector<BlockKey>{{5, 0, 0}}));
  // A record older than what was dropped is not kept; an out-of-order newer one is.
  log.record(1, BlockKey{9, 9, 9});
  log.record(3, BlockKey{7, 7, 7});
  EXPECT_EQ(setOf(log.keysAfter(2)).count(BlockKey{9, 9, 9}), 0u);
  EXPECT_EQ(setOf(log.keysAfter(2)).count(BlockKey{7, 7, 7}), 1u);
  log.clear();
  EXPECT_TRUE(log.keysAfter(2).empty());
  EXPECT_TRUE(log.reaches(2));
}

// Records of a device write-back arrive out of revision order: the log drops whole oldest
// revisions and answers every question it still reaches with exactly the blocks recorded after
// it. Checked against a plain model of the rule (every record kept, the older half dropped by
// revision when full) over a long run of in-order scans with older write-backs between them.
TEST(BlockChangeLogTest, OutOfOrderWriteBacksAreDroppedByRevisionAndAnsweredExactly) {
  constexpr size_t kCapacity = 64;
  BlockChangeLog log(kCapacity);
  struct Rec {
    uint64_t revision;
    BlockKey key;
  };
  std::vector<Rec> model;
  uint64_t model_dropped = 0;
  auto record = [&](uint64_t r, const BlockKey& k) {
    log.record(r, k);
    if (r <= model_dropped) return;
    if (model.size() >= kCapacity) {
      std::stable_sort(model.begin(), model.end(),
                       [](const Rec& a, const Rec& b) { return a.revision < b.revision; });
      const uint64_t cut = model[model.size() / 2 - 1].revision;
      model.erase(std::remove_if(model.begin(), model.end(),
                                 [&](const Rec& x) { return x.revision <= cut; }),
                  model.end());
      model_dropped = std::max(model_dropped, cut);
    }
    model.push_back({r, k});
  };
  uint32_t seed = 12345;
  auto next = [&seed](uint32_t n) {
    seed = seed * 1664525u + 1013904223u;
    return (seed >> 8) % n;
  };
  size_t questions = 0;
  for (uint64_t rev = 1; rev <= 400; ++rev) {
    // A scan's blocks in order, then now and then a write-back of older revisions.
    for (uint32_t i = 0, n = 1 + next(6); i < n; ++i)
      record(rev, BlockKey{int32_t(next(40)), int32_t(rev % 7), 0});
    if (next(4) == 0)
      for (uint32_t i = 0, n = 1 + next(20); i < n; ++i)
        record(rev - std::min<uint64_t>(rev - 1, next(12)), BlockKey{int32_t(next(40)), 9, 1});
    for (uint64_t back : {0ull, 1ull, 3ull, 10ull, 30ull}) {
      const uint64_t asked = rev > back ? rev - back : 0;
      EXPECT_EQ(log.reaches(asked), asked >= model_dropped) << "revision " << rev;
      if (!log.reaches(asked)) continue;
      KeySet want;
      for (const Rec& x : model)
        if (x.revision > asked) want.insert(x.key);
      ASSERT_EQ(setOf(log.keysAfter(asked)), want) << "revision " << rev << ", asked " << asked;
      ++questions;
    }
  }
  EXPECT_GT(model_dropped, 300u);  // the log was full many times over
  EXPECT_GT(questions, 1000u);
}

// BlockMap::masksChangedSince reads the slots the records name and falls back to a look-up by
// key when a block recorded since was erased (its slot free or another block's). Checked against
// the look-ups by key over a long run of random changes, erasures and blocks made again:
// the same blocks in the same order (each block once, where its key first comes in the log),
// and ascending when asked for slot order.
TEST(BlockChangeLogTest, TheRecordedSlotsListWhatTheLookUpsByKeyList) {
  BlockMap blocks;
  struct Rec {
    uint64_t revision;
    BlockKey key;
  };
  std::vector<Rec> records;  // every note, in the log's order
  uint32_t seed = 777;
  auto next = [&seed](uint32_t n) {
    seed = seed * 1664525u + 1013904223u;
    return (seed >> 8) % n;
  };
  auto keyOf = [](uint32_t i) { return BlockKey{int32_t(i % 13), int32_t(i / 13), -2}; };
  size_t fast_questions = 0, erasures = 0;
  for (uint64_t rev = 1; rev <= 300; ++rev) {
    for (uint32_t i = 0, n = 1 + next(25); i < n; ++i) {
      const BlockKey key = keyOf(next(200));
      const BlockIndex slot = blocks.findOrCreate(key);
      const uint64_t before = blocks.meta(slot).masks_at;
      blocks.noteMasksChanged(slot, rev);
      if (before < rev) records.push_back({rev, key});
    }
    // Now and then blocks go (their slots reused by the next blocks made).
    if (next(10) == 0) {
      for (uint32_t i = 0, n = 1 + next(4); i < n; ++i) {
        const BlockKey key = keyOf(next(200));
        if (blocks.find(key) == kNoBlock) continue;
        blocks.erase(key);
        ++erasures;
      }
    }
    for (uint64_t back : {0ull, 1ull, 2ull, 5ull, 20ull, 80ull}) {
      const uint64_t asked = rev > back ? rev - back : 0;
      std::vector<BlockIndex> got;
      ASSERT_TRUE(blocks.masksChangedSince(asked, &got));
      std::vector<BlockIndex> want;
      std::vector<uint8_t> listed(blocks.slotCount(), 0);
      for (const Rec& r : records) {
        if (r.revision <= asked) continue;
        const BlockIndex i = blocks.find(r.key);
        if (i == kNoBlock || listed[i]) continue;
        listed[i] = 1;
        want.push_back(i);
      }
      ASSERT_EQ(got, want) << "revision " << rev << ", asked " << asked;
      // In slot order: the same blocks ascending.
      std::vector<BlockIndex> ascending;
      ASSERT_TRUE(blocks.masksChangedSince(asked, &ascending, BlockMap::ListOrder::kSlots));
      std::sort(want.begin(), want.end());
      ASSERT_EQ(ascending, want) << "revision " << rev << ", asked " << asked;
      // Where no block recorded since was erased, every listed slot holds its key.
      bool erased_since = false;
      for (const Rec& r : records)
        if (r.revision > asked && blocks.find(r.key) == kNoBlock) erased_since = true;
      if (!erased_since) ++fast_questions;
    }
  }
  EXPECT_GT(erasures, 20u);
  EXPECT_GT(fast_questions, 100u);
}

MaskSnapshot snapshot(const Map& map) {
  MaskSnapshot out;
  const BlockView view = map.blockView();
  view.forEach([&](const BlockKey& key, const Block&) { out[key] = *view.findMasks(key); });
  return out;
}

/// Live blocks whose masks differ from `before` (a block new since counts when any of its cells
/// is known; a block gone is not listed).
KeySet differing(const MaskSnapshot& before, const MaskSnapshot& after) {
  KeySet out;
  for (const auto& [key, masks] : after) {
    const auto it = before.find(key);
    if (it == before.end() ? masks != BlockStateMasks() : it->second != masks) out.insert(key);
  }
  return out;
}

/// Runs `step` (one revision) and checks the listed blocks are exactly those whose masks changed.
void expectListedExactly(Map& map, const std::function<void(Map&)>& step, const std::string& what) {
  const MaskSnapshot before = snapshot(map);
  const uint64_t r = map.revision();
  step(map);
  ASSERT_EQ(map.revision(), r + 1) << what;
  const KeySet want = differing(before, snapshot(map));
  const KeySet got = setOf(map.changedBlocksSince(r, BlockChange::kMasks));
  EXPECT_EQ(got.size(), map.changedBlocksSince(r, BlockChange::kMasks).size()) << what;
  EXPECT_EQ(got, want) << what << ": " << got.size() << " listed, " << want.size() << " changed";
  EXPECT_FALSE(want.empty()) << what << " changed no state: the check is empty";
  // The list with masks (what frontiers read instead of cells): the same blocks, each once,
  // each with its current masks.
  std::vector<BlockKey> keys;
  std::vector<BlockStateMasks> masks;
  ASSERT_TRUE(map.masksChangedSince(r, &keys, &masks)) << what;
  ASSERT_EQ(keys.size(), masks.size()) << what;
  EXPECT_EQ(setOf(keys), want) << what;
  EXPECT_EQ(setOf(keys).size(), keys.size()) << what;
  const MaskSnapshot now = snapshot(map);
  for (size_t i = 0; i < keys.size(); ++i) {
    const auto it = now.find(keys[i]);
    ASSERT_NE(it, now.end()) << what;
    EXPECT_EQ(masks[i], it->second) << what;
  }
}

SensorModel lidar() { return SensorModel::spinningLidar(-0.6, 0.6, 0.0, 10.0); }

Eigen::Isometry3d poseAt(int i) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.3 * i, 0.1 * i, 0.02);
  T.linear() = Eigen::AngleAxisd(0.05 * i, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T;
}

TEST(ChangedBlocksTest, MasksListedPerRevisionAreExactlyTheBlocksThatChangedState) {
  MapParams p;
  p.resolution_m = 0.05;
  p.backend = Backend::kCpu;
  p.scans.keep = true;
  Map map(p);
  const PointCloud room = roomScan(4.0, 1.0, 2.0, 16, 360);
  for (int i = 0; i < 4; ++i)
    expectListedExactly(
        map, [&](Map& m) { m.insert(room, poseAt(i), lidar()); }, "scan " + std::to_string(i));
  expectListedExactly(
      map, [](Map& m) { m.remove(1); }, "remove");
  expectListedExactly(
      map,
      [](Map& m) {
        m.clearBox(Eigen::Vector3d(-1.03, -4.2, -1.2), Eigen::Vector3d(0.61, 0.3, 0.4));
      },
      "clearBox");
  expectListedExactly(
      map,
      [](Map& m) {
        m.writeCells([&](CellWriter& w) { w.fillCube(VoxelKey{-10, -10, -10}, 11, 3000); });
      },
      "writeCells");
  Map part = map.extract(Eigen::Vector3d(-4.5, -4.5, -1.5), Eigen::Vector3d(1.0, 4.5, 2.5));
  Eigen::Isometry3d shift = Eigen::Isometry3d::Identity();
  shift.translation() = Eigen::Vector3d(0.4, 0.0, 0.0);  // a whole number of 5 cm cells
  expectListedExactly(
      map, [&](Map& m) { m.merge(part, MergeMode::kAdd, shift); }, "merge");
  expectListedExactly(
      map, [&](Map& m) { m.insert(room, poseAt(6), lidar()); }, "scan after the edits");

  // Over several revisions: every block whose masks changed at any of them, each once, and only
  // live blocks (a block erased and made again may be listed without a change since).
  const std::vector<BlockKey> listed = map.changedBlocksSince(0, BlockChange::kMasks);
  const KeySet all = setOf(listed);
  EXPECT_EQ(all.size(), listed.size());
  const BlockView view = map.blockView();
  size_t walked = 0;
  view.forEach([&](const BlockKey& key, const Block&) {
    if (view.stamps(key).masks_at == 0) return;
    ++walked;
    EXPECT_EQ(all.count(key), 1u);
  });
  for (const BlockKey& key : all) EXPECT_NE(view.findBlock(key), nullptr);
  EXPECT_GE(all.size(), walked);
  EXPECT_GT(walked, 100u);
  std::vector<BlockKey> keys;
  std::vector<BlockStateMasks> masks;
  ASSERT_TRUE(map.masksChangedSince(0, &keys, &masks));
  EXPECT_EQ(setOf(keys), all);
  // A map on the CPU backend keeps no layers on a device.
  EXPECT_EQ(map.deviceView(BlockKey{-100, -100, -100}, BlockKey{100, 100, 100}), nullptr);
  // The sub-map lists its blocks with known cells at its revision.
  EXPECT_EQ(setOf(part.changedBlocksSince(0, BlockChange::kMasks)),
            differing(MaskSnapshot(), snapshot(part)));
}

}  // namespace
}  // namespace fragg::test
