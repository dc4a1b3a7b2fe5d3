// filter_speckles: an occupied cell without an occupied neighbour among its 26 is left out of
// the markers, the occupied cloud and the projected map; cells with a neighbour (also across a
// block boundary, also diagonal) stay; free neighbours do not count.
#include "fragg_map/ros/speckles.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <tuple>

#include "fragg_map/ros/block_markers.h"
#include "fragg_map/ros/occupied_cloud.h"
#include "fragg_map/ros/projected_map.h"
#include "map_fixtures.h"

namespace {

using fragg::CellState;
using fragg::VoxelKey;
using fragg::ros::test::setCell;

const ros::Time kStamp(5, 0);

// A lone occupied cell with a free cell above it, and a diagonal pair across a block boundary.
fragg::Map specklesScene() {
  fragg::Map map(fragg::ros::test::cpuParams(0.1));
  setCell(map, {0, 0, 0}, CellState::kOccupied);  // speckle
  setCell(map, {0, 0, 1}, CellState::kFree);
  setCell(map, {7, 7, 7}, CellState::kOccupied);  // block (0,0,0)
  setCell(map, {8, 8, 8}, CellState::kOccupied);  // block (1,1,1), diagonal neighbour
  return map;
}

std::set<std::tuple<int, int, int>> cloudKeys(const sensor_msgs::PointCloud2& msg) {
  std::set<std::tuple<int, int, int>> keys;
  const float* xyz = reinterpret_cast<const float*>(msg.data.data());
  for (size_t i = 0; i < msg.width; ++i)
    keys.emplace(static_cast<int>(std::floor(xyz[3 * i] / 0.1)),
                 static_cast<int>(std::floor(xyz[3 * i + 1] / 0.1)),
                 static_cast<int>(std::floor(xyz[3 * i + 2] / 0.1)));
  return keys;
}

TEST(Speckles, LoneOccupiedCellsOnly) {
  const fragg::Map map = specklesScene();
  const fragg::BlockView blocks = map.blockView();
  EXPECT_TRUE(fragg::ros::isSpeckle(map, blocks, {0, 0, 0}));
  EXPECT_FALSE(fragg::ros::isSpeckle(map, blocks, {7, 7, 7}));
  EXPECT_FALSE(fragg::ros::isSpeckle(map, blocks, {8, 8, 8}));
  // Brute force over the neighbourhood of every occupied cell agrees.
  for (const VoxelKey& v : {VoxelKey{0, 0, 0}, VoxelKey{7, 7, 7}, VoxelKey{8, 8, 8}}) {
    bool neighbour = false;
    for (const VoxelKey& w : {VoxelKey{0, 0, 0}, VoxelKey{7, 7, 7}, VoxelKey{8, 8, 8}})
      neighbour |= !(w == v) && std::abs(w.x - v.x) <= 1 && std::abs(w.y - v.y) <= 1 &&
                   std::abs(w.z - v.z) <= 1;
    EXPECT_EQ(fragg::ros::isSpeckle(map, blocks, v), !neighbour);
  }
}

TEST(Speckles, OccupiedCloudWithAndWithout) {
  const fragg::Map map = specklesScene();
  using K = std::tuple<int, int, int>;
  EXPECT_EQ(cloudKeys(fragg::ros::occupiedCloud(map, "map", kStamp)),
            (std::set<K>{{0, 0, 0}, {7, 7, 7}, {8, 8, 8}}));
  EXPECT_EQ(cloudKeys(fragg::ros::occupiedCloud(map, "map", kStamp, true)),
            (std::set<K>{{7, 7, 7}, {8, 8, 8}}));
}

TEST(Speckles, ProjectedMapCountsASpeckleNeitherWay) {
  const fragg::Map map = specklesScene();
  const double inf = std::numeric_limits<double>::infinity();
  const nav_msgs::OccupancyGrid with = fragg::ros::projectedMap(map, -inf, inf, "map", kStamp);
  const nav_msgs::OccupancyGrid without =
      fragg::ros::projectedMap(map, -inf, inf, "map", kStamp, true);
  // The grid starts at key (0, 0): column (0, 0) holds the speckle and the free cell above it.
  ASSERT_EQ(with.info.width, 9u);
  EXPECT_EQ(with.data[0], 100);
  EXPECT_EQ(without.data[0], 0);
  EXPECT_EQ(without.data[7 * 9 + 7], 100);
  EXPECT_EQ(without.data[8 * 9 + 8], 100);
}

TEST(Speckles, MarkersLeaveThemOut) {
  const fragg::Map map = specklesScene();
  fragg::ros::MarkerStyle style;
  size_t drawn = 0, drawn_hidden = 0;
  fragg::ros::MarkerLedger ledger, ledger_hidden;
  for (const auto& m : fragg::ros::allBlockMarkers(map, style, kStamp, &ledger).markers)
    drawn += m.points.size();
  style.hide_speckles = true;
  for (const auto& m : fragg::ros::allBlockMarkers(map, style, kStamp, &ledger_hidden).markers)
    drawn_hidden += m.points.size();
  EXPECT_EQ(drawn, 3u);
  EXPECT_EQ(drawn_hidden, 2u);
}

}  // namespace
