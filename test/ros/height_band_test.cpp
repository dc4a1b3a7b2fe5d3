// occupancy_min_z / occupancy_max_z (height_band.h): octomap_server's rule (a cell is shown when
// its cube overlaps the open band) and its use by the occupied and free markers, the occupied
// cloud, the output cache and the projected map.
#include "fragg_map/ros/height_band.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "fragg_map/ros/block_markers.h"
#include "fragg_map/ros/occupied_cloud.h"
#include "fragg_map/ros/output_cache.h"
#include "fragg_map/ros/projected_map.h"
#include "map_fixtures.h"

namespace {

using fragg::ros::HeightBand;
using fragg::ros::MarkerLedger;
using fragg::ros::MarkerStyle;

const ros::Time kStamp(3, 0);
constexpr double kRes = 0.1;

TEST(HeightBand, ACellIsShownWhenItsCubeOverlapsTheOpenBand) {
  const HeightBand band{0.1, 1.0};
  EXPECT_FALSE(band.showsLayer(-1, kRes));  // [-0.1, 0]
  EXPECT_FALSE(band.showsLayer(0, kRes));   // [0, 0.1]: touches min_z only
  EXPECT_TRUE(band.showsLayer(1, kRes));    // [0.1, 0.2]
  EXPECT_TRUE(band.showsLayer(9, kRes));    // [0.9, 1.0]
  EXPECT_FALSE(band.showsLayer(10, kRes));  // [1.0, 1.1]: touches max_z only
  // A bound inside a cell: the cell is shown although its centre lies outside.
  const HeightBand inside{0.17, 0.52};
  EXPECT_TRUE(inside.showsLayer(1, kRes));  // centre 0.15 < 0.17
  EXPECT_TRUE(inside.showsLayer(5, kRes));  // centre 0.55 > 0.52
  EXPECT_FALSE(inside.showsLayer(6, kRes));
  EXPECT_EQ(inside.blockLayers(0, kRes), 0b00111110);
  EXPECT_EQ(inside.blockLayers(1, kRes), 0);
  EXPECT_EQ(inside.blockLayers(-1, kRes), 0);
  // Unbounded (the defaults) shows everything.
  const HeightBand all;
  EXPECT_TRUE(all.unbounded());
  EXPECT_FALSE(inside.unbounded());
  EXPECT_EQ(all.blockLayers(-1000, kRes), 0xff);
  EXPECT_TRUE(all.showsLayer(-(1 << 30), kRes));
  // A zero-thickness band shows the cell that contains it.
  EXPECT_EQ(HeightBand({0.35, 0.35}).blockLayers(0, kRes), 0b00001000);
  EXPECT_THROW((HeightBand{NAN, 1.0}.validate()), fragg::InvalidArgument);
  EXPECT_THROW((HeightBand{1.0, 0.0}.validate()), fragg::InvalidArgument);
  EXPECT_NO_THROW(all.validate());
}

// A column of occupied cells at z layers -4 .. 19 (three blocks high) and a free one beside it.
fragg::Map columnMap() {
  fragg::Map map(fragg::ros::test::cpuParams(kRes));
  for (int z = -4; z < 20; ++z) {
    fragg::ros::test::setCell(map, {0, 0, z}, fragg::CellState::kOccupied);
    fragg::ros::test::setCell(map, {2, 0, z}, fragg::CellState::kFree);
  }
  return map;
}

std::set<int> layersOf(const visualization_msgs::MarkerArray& markers) {
  std::set<int> layers;
  for (const visualization_msgs::Marker& m : markers.markers)
    if (m.action == visualization_msgs::Marker::ADD)
      for (const geometry_msgs::Point& p : m.points)
        layers.insert(static_cast<int>(std::floor(p.z / kRes)));
  return layers;
}

std::set<int> layersOf(const sensor_msgs::PointCloud2& cloud) {
  std::set<int> layers;
  const float* xyz = reinterpret_cast<const float*>(cloud.data.data());
  for (size_t i = 0; i < cloud.width; ++i)
    layers.insert(static_cast<int>(std::floor(xyz[3 * i + 2] / kRes)));
  return layers;
}

const std::set<int> kBandLayers = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};  // (0.17, 1.22)

TEST(HeightBand, MarkersDrawOnlyTheBand) {
  const fragg::Map map = columnMap();
  for (const fragg::CellState state : {fragg::CellState::kOccupied, fragg::CellState::kFree}) {
    MarkerStyle style;
    style.state = state;
    style.heights = {0.17, 1.22};
    MarkerLedger full_ledger, changed_ledger;
    EXPECT_EQ(layersOf(fragg::ros::allBlockMarkers(map, style, kStamp, &full_ledger)), kBandLayers);
    EXPECT_EQ(layersOf(fragg::ros::changedBlockMarkers(map, style, kStamp, &changed_ledger)),
              kBandLayers);
    // The block under the band (layers -8 .. -1) holds cells but draws none.
    EXPECT_EQ(full_ledger.idOf({0, 0, -1}), -1);
    EXPECT_EQ(full_ledger.shownBlocks(), 2u);
    // Without a band every layer is drawn.
    MarkerLedger all_ledger;
    style.heights = HeightBand();
    EXPECT_EQ(layersOf(fragg::ros::allBlockMarkers(map, style, kStamp, &all_ledger)).size(), 24u);
  }
}

TEST(HeightBand, OccupiedCloudCacheAndProjectedMapFollowTheBand) {
  fragg::Map map = columnMap();
  EXPECT_EQ(layersOf(fragg::ros::occupiedCloud(map, "map", kStamp, false, {0.17, 1.22})),
            kBandLayers);
  EXPECT_EQ(layersOf(fragg::ros::occupiedCloud(map, "map", kStamp)).size(), 24u);
  fragg::ros::OutputCacheOptions o;
  o.occupancy_min_z_m = 0.17;
  o.occupancy_max_z_m = 1.22;
  fragg::ros::MapOutputCache cache(o);
  cache.update(map);
  EXPECT_EQ(layersOf(cache.occupiedCloud("map", kStamp)), kBandLayers);
  EXPECT_EQ(cache.occupiedCells(), kBandLayers.size());
  // The projected map: a band of the free column only is free, of both occupied.
  const nav_msgs::OccupancyGrid band = fragg::ros::projectedMap(map, 0.17, 1.22, "map", kStamp);
  ASSERT_EQ(band.info.width, 3u);
  EXPECT_EQ(band.data[0], 100);
  EXPECT_EQ(band.data[2], 0);
  // A band that only touches the column's top (1.9 .. 2.0 is its last cell): nothing shown.
  const nav_msgs::OccupancyGrid above = fragg::ros::projectedMap(map, 2.0, 3.0, "map", kStamp);
  EXPECT_EQ(above.data[0], -1);
  EXPECT_EQ(above.data[2], -1);
  const nav_msgs::OccupancyGrid cache_grid = cache.projectedMap("map", kStamp);
  EXPECT_EQ(cache_grid.data, band.data);
}

}  // namespace
