// Free-only points (PointCloud::free_only, octomap_server's ground points): their rays clear up
// to the point and leave the point's own cell as it was.
#include <gtest/gtest.h>

#include <cstdlib>

#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "test_scenes.h"

namespace fragg {
namespace {

using test::cloudOf;
using test::sensorAtVoxelCentre;

const Cell* cellAt(const Map& m, int x, int y, int z) { return m.findCell(VoxelKey{x, y, z}); }

TEST(FreeOnlyPointsTest, RayClearsUpToThePointAndLeavesItsCell) {
  Map map;
  PointCloud cloud = cloudOf({{1.0f, 0.f, 0.f}});
  cloud.free_only = {1};
  const InsertStats s = map.insert(cloud, sensorAtVoxelCentre(), SensorModel::autoFromCloud());
  EXPECT_EQ(s.rays_hit, 0u);
  EXPECT_EQ(s.rays_free_only, 1u);
  for (int x = 0; x < 20; ++x) {
    const Cell* c = cellAt(map, x, 0, 0);
    ASSERT_NE(c, nullptr) << x;
    EXPECT_EQ(map.state(*c), CellState::kFree) << x;
    EXPECT_EQ(c->hits, 0);
  }
  const Cell* end = cellAt(map, 20, 0, 0);
  EXPECT_TRUE(end == nullptr || !end->observed());
  EXPECT_EQ(map.knownVoxelCount(), 20u);
}

TEST(FreeOnlyPointsTest, FlagsZeroMeanOrdinaryHits) {
  Map a, b;
  PointCloud flagged = cloudOf({{1.0f, 0.f, 0.f}, {0.f, 1.0f, 0.f}});
  flagged.free_only = {0, 0};
  PointCloud plain = cloudOf({{1.0f, 0.f, 0.f}, {0.f, 1.0f, 0.f}});
  a.insert(flagged, sensorAtVoxelCentre(), SensorModel::autoFromCloud());
  b.insert(plain, sensorAtVoxelCentre(), SensorModel::autoFromCloud());
  EXPECT_EQ(a.knownVoxelCount(), b.knownVoxelCount());
  EXPECT_EQ(a.state(*cellAt(a, 20, 0, 0)), CellState::kOccupied);
  EXPECT_EQ(a.state(*cellAt(a, 0, 20, 0)), CellState::kOccupied);
}

TEST(FreeOnlyPointsTest, HitOfTheSameScanWinsOverAFreeOnlyRay) {
  Map map;
  // The free-only ray to 1 m passes through the hit at 0.5 m (cell 10).
  PointCloud cloud = cloudOf({{0.5f, 0.f, 0.f}, {1.0f, 0.f, 0.f}});
  cloud.free_only = {0, 1};
  map.insert(cloud, sensorAtVoxelCentre(), SensorModel::autoFromCloud());
  EXPECT_EQ(map.state(*cellAt(map, 10, 0, 0)), CellState::kOccupied);
  EXPECT_EQ(map.state(*cellAt(map, 15, 0, 0)), CellState::kFree);
  const Cell* end = cellAt(map, 20, 0, 0);
  EXPECT_TRUE(end == nullptr || !end->observed());
}

TEST(FreeOnlyPointsTest, FreeOnlyPointBeyondMaxRangeIsClipped) {
  Map map;
  PointCloud cloud = cloudOf({{10.f, 0.f, 0.f}});
  cloud.free_only = {1};
  map.insert(cloud, sensorAtVoxelCentre(), SensorModel::autoFromCloud(0.0, 2.0));
  EXPECT_EQ(map.state(*cellAt(map, 39, 0, 0)), CellState::kFree);
  EXPECT_EQ(map.query({5.0, 0.0, 0.0}), CellState::kUnknown);
}

/// A room scanned from 1 m above its floor (z = 0), floor points flagged as octomap_server's
/// filter_ground would: the floor the sensor sees is free, never occupied; the walls are hits.
TEST(FreeOnlyPointsTest, FlaggedFloorIsFreeAndWallsStayOccupied) {
  MapParams params;
  params.resolution_m = 0.1;
  Map ground_free(params), plain(params);
  Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
  T_map_sensor.translation() = Eigen::Vector3d(0.05, 0.05, 1.0);
  PointCloud cloud = test::roomScan(3.0, 1.0, 1.5, 32, 360);
  cloud.free_only.resize(cloud.size());
  size_t floor_points = 0;
  for (size_t i = 0; i < cloud.size(); ++i) {
    const double z_map = (T_map_sensor * cloud.points_S[i].cast<double>()).z();
    cloud.free_only[i] = z_map < 0.02 ? 1 : 0;
    floor_points += cloud.free_only[i];
  }
  ASSERT_GT(floor_points, 1000u);
  const InsertStats s = ground_free.insert(cloud, T_map_sensor, SensorModel::autoFromCloud());
  EXPECT_EQ(s.rays_free_only, floor_points);
  PointCloud unflagged = cloud;
  unflagged.free_only.clear();
  plain.insert(unflagged, T_map_sensor, SensorModel::autoFromCloud());

  // Floor layers: z keys -1 and 0 (the floor points lie on z = 0, either side in float), away
  // from the walls (x, y = +-3 m), whose feet hold hits in those layers.
  auto floorCell = [](const VoxelKey& k) {
    return k.z <= 0 && std::abs(k.x) <= 27 && std::abs(k.y) <= 27;
  };
  size_t floor_occupied = 0, floor_free = 0, plain_floor_occupied = 0;
  size_t above_occupied = 0, above_differ = 0;
  ground_free.forEachBlock([&](const BlockKey& bk, const Block& b) {
    for (int c = 0; c < kCellsPerBlock; ++c) {
      if (!b.cells[c].observed()) continue;
      const VoxelKey k = voxelKeyOf(bk, c);
      const CellState st = ground_free.state(b.cells[c]);
      if (floorCell(k)) {
        floor_occupied += st == CellState::kOccupied;
        floor_free += k.z == 0 && st == CellState::kFree;
      }
    }
  });
  plain.forEachBlock([&](const BlockKey& bk, const Block& b) {
    for (int c = 0; c < kCellsPerBlock; ++c) {
      if (!b.cells[c].observed()) continue;
      const VoxelKey k = voxelKeyOf(bk, c);
      const bool occupied = plain.state(b.cells[c]) == CellState::kOccupied;
      if (k.z <= 0) {  // floor layers (the wall feet there hold floor points too)
        plain_floor_occupied += floorCell(k) && occupied;
        continue;
      }
      // Above the floor both maps hold the same hits (free-only rays never add one).
      above_occupied += occupied;
      const Cell* other = ground_free.findCell(k);
      const bool other_occupied =
          other != nullptr && ground_free.state(*other) == CellState::kOccupied;
      above_differ += occupied != other_occupied;
    }
  });
  EXPECT_EQ(floor_occupied, 0u);
  EXPECT_GT(floor_free, 500u);
  EXPECT_GT(plain_floor_occupied, 500u);
  EXPECT_GT(above_occupied, 1000u);
  EXPECT_EQ(above_differ, 0u);
}

TEST(FreeOnlyPointsTest, HeightBandKeepsTheFlagsOfThePointsItKeeps) {
  MapParams params;
  params.height_filter.min_z_m = -0.5;
  params.height_filter.max_z_m = 0.5;
  Map map(params);
  // The first point is dropped by the band; the flags must stay with their points.
  PointCloud cloud = cloudOf({{0.f, 0.f, 2.f}, {1.0f, 0.f, 0.f}, {0.f, 1.0f, 0.f}});
  cloud.free_only = {0, 1, 0};
  map.insert(cloud, sensorAtVoxelCentre(), SensorModel::autoFromCloud());
  const Cell* free_end = cellAt(map, 20, 0, 0);
  EXPECT_TRUE(free_end == nullptr || !free_end->observed());
  EXPECT_EQ(map.state(*cellAt(map, 0, 20, 0)), CellState::kOccupied);
}

TEST(FreeOnlyPointsTest, WrongFlagCountIsRejectedAndMapUntouched) {
  Map map;
  PointCloud cloud = cloudOf({{1.0f, 0.f, 0.f}, {0.f, 1.0f, 0.f}});
  cloud.free_only = {1};
  EXPECT_THROW(map.insert(cloud, sensorAtVoxelCentre(), SensorModel::autoFromCloud()),
               InvalidArgument);
  EXPECT_EQ(map.blockCount(), 0u);
  EXPECT_EQ(map.scanCount(), 0u);
}

TEST(FreeOnlyPointsTest, KeptScanWithFreeOnlyPointsCannotBeRemoved) {
  MapParams params;
  params.scans.keep = true;
  Map map(params);
  PointCloud flagged = cloudOf({{1.0f, 0.f, 0.f}, {0.f, 1.0f, 0.f}});
  flagged.free_only = {1, 0};
  PointCloud none_set = flagged;
  none_set.free_only = {0, 0};
  const ScanId a = map.insert(flagged, sensorAtVoxelCentre(), SensorModel::autoFromCloud()).scan_id;
  const ScanId b =
      map.insert(none_set, sensorAtVoxelCentre(), SensorModel::autoFromCloud()).scan_id;
  const size_t known = map.knownVoxelCount();
  EXPECT_THROW(map.remove(a), InvalidArgument);
  EXPECT_EQ(map.knownVoxelCount(), known);
  EXPECT_NO_THROW(map.remove(b));
}

}  // namespace
}  // namespace fragg
