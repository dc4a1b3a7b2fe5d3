// Map -> per-block CUBE_LIST markers: content, incrementality (Map::changedBlocksSince), DELETE
// for emptied and erased blocks, full republish, height colours.
#include "fragg_map/ros/block_markers.h"

#include <gtest/gtest.h>

#include <map>
#include <set>
#include <tuple>

#include "fragg_map/ros/height_color.h"
#include "map_fixtures.h"

namespace {

using fragg::ros::MarkerLedger;
using fragg::ros::MarkerStyle;
using visualization_msgs::Marker;
using visualization_msgs::MarkerArray;

const ros::Time kStamp(12, 34);

size_t countAction(const MarkerArray& a, int32_t action) {
  size_t n = 0;
  for (const Marker& m : a.markers) n += m.action == action;
  return n;
}

// The block a marker's points lie in (all of them must share it).
fragg::BlockKey blockOfMarker(const fragg::Map& map, const Marker& m) {
  const fragg::BlockKey key =
      fragg::blockKeyOf(map.keyOf(Eigen::Vector3d(m.points[0].x, m.points[0].y, m.points[0].z)));
  for (const auto& p : m.points)
    EXPECT_EQ(fragg::blockKeyOf(map.keyOf(Eigen::Vector3d(p.x, p.y, p.z))), key);
  return key;
}

TEST(BlockMarkers, FirstUpdateShowsEveryOccupiedCellOncePerBlock) {
  fragg::Map map(fragg::ros::test::cpuParams());
  fragg::ros::test::insertWall(map, Eigen::Vector3d::Zero(), 3.0);
  MarkerLedger ledger;
  MarkerStyle style;
  const MarkerArray a = fragg::ros::changedBlockMarkers(map, style, kStamp, &ledger);
  const auto occupied = fragg::ros::test::centresIn(map, fragg::CellState::kOccupied);
  ASSERT_FALSE(occupied.empty());
  size_t points = 0;
  std::set<int32_t> ids;
  std::set<std::tuple<int, int, int>> blocks;
  for (const Marker& m : a.markers) {
    EXPECT_EQ(m.action, Marker::ADD);
    EXPECT_EQ(m.type, Marker::CUBE_LIST);
    EXPECT_EQ(m.header.frame_id, "map");
    EXPECT_EQ(m.header.stamp, kStamp);
    EXPECT_EQ(m.ns, "occupied");
    EXPECT_DOUBLE_EQ(m.scale.x, 0.1);
    ASSERT_FALSE(m.points.empty());
    EXPECT_EQ(m.points.size(), m.colors.size());
    const fragg::BlockKey key = blockOfMarker(map, m);
    EXPECT_TRUE(blocks.insert({key.x, key.y, key.z}).second) << "two markers for one block";
    EXPECT_TRUE(ids.insert(m.id).second) << "duplicate id " << m.id;
    EXPECT_EQ(ledger.idOf(key), m.id);
    for (const auto& p : m.points)
      EXPECT_EQ(map.query(Eigen::Vector3d(p.x, p.y, p.z)), fragg::CellState::kOccupied);
    points += m.points.size();
  }
  EXPECT_EQ(points, occupied.size());
  EXPECT_EQ(ledger.shownBlocks(), a.markers.size());
  EXPECT_EQ(ledger.publishedRevision(), map.revision());
}

using KeySet = std::set<std::tuple<int32_t, int32_t, int32_t>>;

// What a subscriber shows after applying marker arrays in order: the voxels of each marker id.
using ShownVoxels = std::map<int32_t, KeySet>;

void apply(const fragg::Map& map, const MarkerArray& a, ShownVoxels* shown) {
  for (const Marker& m : a.markers) {
    if (m.action == Marker::DELETEALL) {
      shown->clear();
    } else if (m.action == Marker::DELETE) {
      EXPECT_EQ(shown->erase(m.id), 1u) << "DELETE of a marker that is not shown";
    } else {
      KeySet& voxels = (*shown)[m.id];
      voxels.clear();
      for (const auto& p : m.points) {
        const fragg::VoxelKey v = map.keyOf(Eigen::Vector3d(p.x, p.y, p.z));
        voxels.insert({v.x, v.y, v.z});
      }
    }
  }
}

KeySet allShown(const ShownVoxels& shown) {
  KeySet all;
  for (const auto& entry : shown) all.insert(entry.second.begin(), entry.second.end());
  return all;
}

KeySet occupiedVoxels(const fragg::Map& map) {
  KeySet out;
  for (const Eigen::Vector3d& c : fragg::ros::test::centresIn(map, fragg::CellState::kOccupied)) {
    const fragg::VoxelKey v = map.keyOf(c);
    out.insert({v.x, v.y, v.z});
  }
  return out;
}

// marker_rate: a throttled topic skips updates; the next one carries every block changed since
// its last (by revision), so its subscriber ends up with the same voxels as one that got every
// update, including cells that appeared and vanished in between.
TEST(BlockMarkers, SkippedUpdatesAccumulateNothingIsLost) {
  fragg::Map map(fragg::ros::test::cpuParams());
  const fragg::VoxelKey lone{1, 2, 3};
  fragg::ros::test::setCell(map, lone, fragg::CellState::kOccupied);
  fragg::ros::test::insertWall(map, Eigen::Vector3d::Zero(), 3.0);
  MarkerLedger every, throttled;
  ShownVoxels every_view, throttled_view;
  apply(map, fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &every), &every_view);
  apply(map, fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &throttled),
        &throttled_view);
  ASSERT_EQ(allShown(throttled_view).count({lone.x, lone.y, lone.z}), 1u);
  // Three changes the throttled topic does not publish: a new wall, the lone cell freed (its
  // block emptied), a wall seen from farther away.
  fragg::ros::test::insertWall(map, Eigen::Vector3d(0.0, 10.0, 0.0), 3.0);
  apply(map, fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &every), &every_view);
  fragg::ros::test::setCell(map, lone, fragg::CellState::kFree);
  apply(map, fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &every), &every_view);
  fragg::ros::test::insertWall(map, Eigen::Vector3d(-2.0, 0.0, 0.0), 5.5);
  apply(map, fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &every), &every_view);
  const MarkerArray catch_up =
      fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &throttled);
  EXPECT_EQ(countAction(catch_up, Marker::DELETE), 1u);  // the lone cell's block
  apply(map, catch_up, &throttled_view);
  const KeySet expected = occupiedVoxels(map);
  EXPECT_EQ(expected.count({lone.x, lone.y, lone.z}), 0u);
  EXPECT_EQ(allShown(every_view), expected);
  EXPECT_EQ(allShown(throttled_view), expected);
  EXPECT_EQ(throttled.shownBlocks(), every.shownBlocks());
  EXPECT_EQ(throttled.publishedRevision(), map.revision());
}

TEST(BlockMarkers, NothingChangedMeansNothingSent) {
  fragg::Map map(fragg::ros::test::cpuParams());
  fragg::ros::test::insertWall(map, Eigen::Vector3d::Zero(), 3.0);
  MarkerLedger ledger;
  fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &ledger);
  EXPECT_TRUE(fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &ledger).markers.empty());
}

TEST(BlockMarkers, SecondScanSendsOnlyTheBlocksItChanged) {
  fragg::Map map(fragg::ros::test::cpuParams());
  fragg::ros::test::insertWall(map, Eigen::Vector3d::Zero(), 3.0);
  MarkerLedger ledger;
  const MarkerArray first = fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &ledger);
  ASSERT_FALSE(first.markers.empty());
  const uint64_t before = map.revision();
  // A second wall 10 m to the side (y in [9, 11] m): its rays never reach the first wall's
  // blocks (y in [-1, 1] m), so only its own blocks change.
  fragg::ros::test::insertWall(map, Eigen::Vector3d(0.0, 10.0, 0.0), 3.0);
  const MarkerArray second = fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &ledger);
  std::set<std::tuple<int, int, int>> far_occupied_blocks;
  for (const Eigen::Vector3d& c : fragg::ros::test::centresIn(map, fragg::CellState::kOccupied)) {
    const fragg::BlockKey k = fragg::blockKeyOf(map.keyOf(c));
    if (c.y() > 8.0) far_occupied_blocks.insert({k.x, k.y, k.z});
  }
  ASSERT_FALSE(far_occupied_blocks.empty());
  EXPECT_EQ(second.markers.size(), far_occupied_blocks.size());
  std::set<int32_t> first_ids;
  for (const Marker& m : first.markers) first_ids.insert(m.id);
  for (const Marker& m : second.markers) {
    ASSERT_EQ(m.action, Marker::ADD);
    const fragg::BlockKey k = blockOfMarker(map, m);
    EXPECT_EQ(far_occupied_blocks.count({k.x, k.y, k.z}), 1u);
    EXPECT_GT(map.blockView().stamps(k).changed_at, before);
    EXPECT_EQ(first_ids.count(m.id), 0u) << "a new block reused a shown block's id";
  }
  EXPECT_EQ(ledger.shownBlocks(), first.markers.size() + second.markers.size());
  // Re-observing the first wall: whatever it resends keeps the old ids.
  fragg::ros::test::insertWall(map, Eigen::Vector3d::Zero(), 3.0);
  const MarkerArray third = fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &ledger);
  for (const Marker& m : third.markers) EXPECT_EQ(first_ids.count(m.id), 1u);
}

TEST(BlockMarkers, BlockIsResentOnlyWhenItsDrawnCellsChange) {
  fragg::Map map(fragg::ros::test::cpuParams());
  const fragg::VoxelKey a{1, 2, 3}, a_free{2, 2, 3}, a_more{3, 2, 3};
  fragg::ros::test::setCell(map, a, fragg::CellState::kOccupied);
  MarkerLedger ledger;
  ASSERT_EQ(fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &ledger).markers.size(),
            1u);
  // Same block, a free cell changes: the block's changed_at moves, its occupied cells do not.
  fragg::ros::test::setCell(map, a_free, fragg::CellState::kFree);
  ASSERT_GT(map.blockView().stamps(fragg::blockKeyOf(a)).changed_at, ledger.publishedRevision());
  EXPECT_TRUE(fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &ledger).markers.empty());
  // A second occupied cell: the block is sent again, whole, under the same id.
  const int32_t id = ledger.idOf(fragg::blockKeyOf(a));
  fragg::ros::test::setCell(map, a_more, fragg::CellState::kOccupied);
  const MarkerArray again = fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &ledger);
  ASSERT_EQ(again.markers.size(), 1u);
  EXPECT_EQ(again.markers[0].id, id);
  EXPECT_EQ(again.markers[0].action, Marker::ADD);
  EXPECT_EQ(again.markers[0].points.size(), 2u);
}

TEST(BlockMarkers, ColoursFollowHeight) {
  fragg::Map map(fragg::ros::test::cpuParams(0.5));
  fragg::ros::test::setCell(map, {0, 0, 0}, fragg::CellState::kOccupied);  // z 0.25 m
  fragg::ros::test::setCell(map, {0, 0, 7}, fragg::CellState::kOccupied);  // z 3.75 m
  MarkerLedger ledger;
  MarkerStyle style;
  style.color_min_z_m = 0.0;
  style.color_max_z_m = 4.0;
  const MarkerArray a = fragg::ros::changedBlockMarkers(map, style, kStamp, &ledger);
  ASSERT_EQ(a.markers.size(), 1u);
  const Marker& m = a.markers[0];
  ASSERT_EQ(m.points.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const auto want = fragg::ros::heightColor(m.points[i].z, 0.0, 4.0, 1.f);
    EXPECT_FLOAT_EQ(m.colors[i].r, want.r);
    EXPECT_FLOAT_EQ(m.colors[i].g, want.g);
    EXPECT_FLOAT_EQ(m.colors[i].b, want.b);
  }
  EXPECT_NE(m.colors[0].g, m.colors[1].g);
}

TEST(BlockMarkers, BlockThatLosesItsOccupiedCellsIsDeleted) {
  fragg::Map map(fragg::ros::test::cpuParams());
  const fragg::VoxelKey a{1, 2, 3}, b{40, 2, 3};
  fragg::ros::test::setCell(map, a, fragg::CellState::kOccupied);
  fragg::ros::test::setCell(map, b, fragg::CellState::kOccupied);
  MarkerLedger ledger;
  const MarkerArray first = fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &ledger);
  ASSERT_EQ(first.markers.size(), 2u);
  const int32_t id_a = ledger.idOf(fragg::blockKeyOf(a));
  ASSERT_GE(id_a, 0);
  fragg::ros::test::setCell(map, a, fragg::CellState::kFree);  // the block still exists
  const MarkerArray second = fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &ledger);
  ASSERT_EQ(second.markers.size(), 1u);
  EXPECT_EQ(second.markers[0].action, Marker::DELETE);
  EXPECT_EQ(second.markers[0].id, id_a);
  EXPECT_EQ(second.markers[0].ns, "occupied");
  EXPECT_EQ(ledger.idOf(fragg::blockKeyOf(a)), -1);
  EXPECT_EQ(ledger.shownBlocks(), 1u);
  // The free-space topic shows that block now.
  MarkerLedger free_ledger;
  MarkerStyle free_style;
  free_style.ns = "free";
  free_style.state = fragg::CellState::kFree;
  const MarkerArray free = fragg::ros::changedBlockMarkers(map, free_style, kStamp, &free_ledger);
  ASSERT_EQ(free.markers.size(), 1u);
  EXPECT_EQ(free.markers[0].points.size(), 1u);
  EXPECT_EQ(free.markers[0].ns, "free");
}

TEST(BlockMarkers, ClearedBoxDeletesTheErasedBlocks) {
  fragg::Map map(fragg::ros::test::cpuParams());
  fragg::ros::test::insertWall(map, Eigen::Vector3d::Zero(), 3.0);
  MarkerLedger ledger;
  const MarkerArray first = fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &ledger);
  std::set<int32_t> shown;
  for (const Marker& m : first.markers) shown.insert(m.id);
  map.clearBox(Eigen::Vector3d(-100, -100, -100), Eigen::Vector3d(100, 100, 100));
  ASSERT_EQ(map.blockCount(), 0u);
  const MarkerArray second = fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &ledger);
  EXPECT_EQ(countAction(second, Marker::DELETE), shown.size());
  EXPECT_EQ(second.markers.size(), shown.size());
  for (const Marker& m : second.markers) EXPECT_EQ(shown.count(m.id), 1u);
  EXPECT_EQ(ledger.shownBlocks(), 0u);
}

// latch: a subscriber that connects late gets what the others see, under the same ids, so the
// increments that follow apply to its view as to theirs.
TEST(BlockMarkers, LateSubscriberFollowsTheIncrementsAfterItsSnapshot) {
  fragg::Map map(fragg::ros::test::cpuParams());
  fragg::ros::test::insertWall(map, Eigen::Vector3d::Zero(), 3.0);
  MarkerLedger topic;
  ShownVoxels early, late;
  apply(map, fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &topic), &early);
  fragg::ros::test::insertWall(map, Eigen::Vector3d(0.0, 10.0, 0.0), 3.0);
  apply(map, fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &topic), &early);
  const size_t shown_before = topic.shownBlocks();
  const MarkerArray snapshot = fragg::ros::shownBlockMarkers(map, MarkerStyle(), kStamp, topic);
  EXPECT_EQ(topic.shownBlocks(), shown_before);  // the topic's ledger is left alone
  ASSERT_EQ(snapshot.markers.size(), shown_before + 1);
  EXPECT_EQ(snapshot.markers[0].action, Marker::DELETEALL);
  apply(map, snapshot, &late);
  EXPECT_EQ(late, early);  // same ids, same cells
  // Later changes, one of them deleting a block both views show.
  const fragg::VoxelKey lone{40, 40, 40};
  fragg::ros::test::setCell(map, lone, fragg::CellState::kOccupied);
  const MarkerArray add = fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &topic);
  apply(map, add, &early);
  apply(map, add, &late);
  fragg::ros::test::setCell(map, lone, fragg::CellState::kFree);
  const MarkerArray del = fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &topic);
  EXPECT_EQ(countAction(del, Marker::DELETE), 1u);
  apply(map, del, &early);
  apply(map, del, &late);
  EXPECT_EQ(late, early);
  EXPECT_EQ(allShown(late), occupiedVoxels(map));
}

TEST(BlockMarkers, FullRepublishStartsWithDeleteAll) {
  fragg::Map map(fragg::ros::test::cpuParams());
  fragg::ros::test::insertWall(map, Eigen::Vector3d::Zero(), 3.0);
  MarkerLedger incremental, full;
  const MarkerArray inc = fragg::ros::changedBlockMarkers(map, MarkerStyle(), kStamp, &incremental);
  const MarkerArray all = fragg::ros::allBlockMarkers(map, MarkerStyle(), kStamp, &full);
  ASSERT_EQ(all.markers.size(), inc.markers.size() + 1);
  EXPECT_EQ(all.markers[0].action, Marker::DELETEALL);
  EXPECT_EQ(countAction(all, Marker::ADD), inc.markers.size());
  EXPECT_EQ(full.shownBlocks(), incremental.shownBlocks());
  // After a reset the full republish is the DELETEALL alone.
  map.reset();
  const MarkerArray after_reset = fragg::ros::allBlockMarkers(map, MarkerStyle(), kStamp, &full);
  ASSERT_EQ(after_reset.markers.size(), 1u);
  EXPECT_EQ(after_reset.markers[0].action, Marker::DELETEALL);
  EXPECT_EQ(full.shownBlocks(), 0u);
}

TEST(HeightColor, RampEndsAndClamping) {
  const auto low = fragg::ros::heightColor(-5.0, 0.0, 2.0, 0.5f);
  EXPECT_FLOAT_EQ(low.r, 1.f);
  EXPECT_FLOAT_EQ(low.g, 0.f);
  EXPECT_FLOAT_EQ(low.b, 0.f);
  EXPECT_FLOAT_EQ(low.a, 0.5f);
  const auto high = fragg::ros::heightColor(9.0, 0.0, 2.0, 1.f);
  EXPECT_FLOAT_EQ(high.r, 1.f);
  EXPECT_FLOAT_EQ(high.g, 0.f);
  EXPECT_FLOAT_EQ(high.b, 1.f);
  const auto mid = fragg::ros::heightColor(1.0, 0.0, 2.0, 1.f);  // hue 2.5 sectors: cyan-green
  EXPECT_FLOAT_EQ(mid.r, 0.f);
  EXPECT_FLOAT_EQ(mid.g, 1.f);
  EXPECT_FLOAT_EQ(mid.b, 0.5f);
}

}  // namespace
