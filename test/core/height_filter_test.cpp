// MapParams::height_filter (points dropped by map-frame height, counted in InsertStats) and
// InsertStats::sensor (the model a scan was integrated with).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "test_scenes.h"

namespace fragg {
namespace {

MapParams cpuParams(double min_z_m, double max_z_m) {
  MapParams p;
  p.backend = Backend::kCpu;
  p.threads = 1;
  p.resolution_m = 0.1;
  p.height_filter.min_z_m = min_z_m;
  p.height_filter.max_z_m = max_z_m;
  return p;
}

// The sensor 1 m up, pitched so that its x axis points along map -z: a sensor-frame point
// (d, 0, 0) lies at map height 1 - d. The filter must use the map frame, not the sensor's.
Eigen::Isometry3d lookingDown() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.05, 0.05, 1.0);
  T.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  return T;
}

TEST(HeightFilter, DropsPointsOutsideTheBandInTheMapFrame) {
  Map map(cpuParams(-0.5, 0.7));
  // Map heights 0.55 (kept), -1.05 (below), 0.25 (kept), 1.45 (above; behind the sensor).
  const PointCloud cloud = test::cloudOf(
      {{0.45f, 0.f, 0.f}, {2.05f, -0.3f, 0.f}, {0.75f, 0.3f, 0.f}, {-0.45f, 0.6f, 0.f}});
  const InsertStats s = map.insert(cloud, lookingDown(), SensorModel::autoFromCloud());
  EXPECT_EQ(s.dropped_height, 2u);
  EXPECT_EQ(s.rays_hit, 2u);
  EXPECT_EQ(s.points_in, 4u);
  EXPECT_EQ(s.dropped_invalid, 0u);
  EXPECT_EQ(map.query({0.05, 0.05, 0.55}), CellState::kOccupied);
  EXPECT_EQ(map.query({0.05, 0.35, 0.25}), CellState::kOccupied);
  EXPECT_EQ(map.query({0.05, -0.25, -1.05}), CellState::kUnknown);  // the dropped hits
  EXPECT_EQ(map.query({0.05, 0.65, 1.45}), CellState::kUnknown);
}

TEST(HeightFilter, OffByDefaultAndCountsNothing) {
  Map map(
      cpuParams(-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()));
  const PointCloud cloud = test::cloudOf({{0.45f, 0.f, 0.f}, {2.05f, -0.3f, 0.f}});
  const InsertStats s = map.insert(cloud, lookingDown(), SensorModel::autoFromCloud());
  EXPECT_EQ(s.dropped_height, 0u);
  EXPECT_EQ(s.rays_hit, 2u);
  EXPECT_EQ(map.query({0.05, -0.25, -1.05}), CellState::kOccupied);
}

TEST(HeightFilter, OrganisedCloudsKeepTheirLayoutAndClearNoFloor) {
  // A 3 x 2 organised cloud looking down: every pixel hits map z = 0.55 but the middle one of
  // the second row, which hits the floor at z = 0.05, below the band. With clear_no_return_rays
  // a NaN pixel between two valid ones would become a no-return ray through the floor; a
  // filtered pixel must not.
  MapParams p = cpuParams(0.3, 10.0);
  p.clear_no_return_rays = true;
  Map map(p);
  PointCloud cloud;
  cloud.width = 3;
  cloud.height = 2;
  for (int row = 0; row < 2; ++row)
    for (int col = 0; col < 3; ++col)
      cloud.points_S.push_back(
          Eigen::Vector3f(row == 1 && col == 1 ? 0.95f : 0.45f, 0.1f * (col - 1), 0.f));
  const InsertStats s = map.insert(cloud, lookingDown(), SensorModel::autoFromCloud(0.0, 5.0));
  EXPECT_EQ(s.dropped_height, 1u);
  EXPECT_EQ(s.rays_hit, 5u);
  EXPECT_EQ(s.rays_no_return, 0u);
  EXPECT_EQ(s.dropped_invalid, 0u);
  EXPECT_EQ(s.points_in, 6u);
  EXPECT_EQ(map.query({0.05, 0.05, 0.55}), CellState::kOccupied);
  EXPECT_EQ(map.query({0.05, 0.05, 0.05}), CellState::kUnknown);   // the floor: not inserted
  EXPECT_EQ(map.query({0.05, 0.05, -1.05}), CellState::kUnknown);  // not cleared through it
}

TEST(HeightFilter, KeptScansHoldTheFilteredPoints) {
  MapParams p = cpuParams(-0.5, 0.7);
  p.scans.keep = true;
  Map map(p);
  const PointCloud cloud = test::cloudOf({{0.45f, 0.f, 0.f}, {2.05f, 0.f, 0.f}});
  const InsertStats s = map.insert(cloud, lookingDown(), SensorModel::autoFromCloud());
  ASSERT_EQ(s.dropped_height, 1u);
  // Moving the scan does not bring the dropped point back.
  Eigen::Isometry3d moved = lookingDown();
  moved.translation().x() += 1.0;
  map.correctPoses({{s.scan_id, moved}});
  EXPECT_EQ(map.query({1.05, 0.05, 0.55}), CellState::kOccupied);
  EXPECT_EQ(map.query({1.05, 0.05, -1.05}), CellState::kUnknown);
}

TEST(HeightFilter, ValidateNamesTheField) {
  MapParams p;
  p.height_filter.min_z_m = 2.0;
  p.height_filter.max_z_m = 1.0;
  try {
    p.validate();
    FAIL() << "an inverted band was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("height_filter.min_z_m", 0), 0u) << e.what();
  }
  p.height_filter.min_z_m = std::nan("");
  EXPECT_THROW(p.validate(), InvalidArgument);
  p.height_filter.min_z_m = 1.0;  // a band of one height is fine
  EXPECT_NO_THROW(p.validate());
}

TEST(InsertStatsSensor, AnAutoModelComesBackResolved) {
  Map map(
      cpuParams(-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()));
  // Every point in front of the sensor along +z: a pinhole about the z axis.
  const PointCloud cloud = test::cloudOf({{0.2f, 0.1f, 3.f}, {-0.2f, -0.1f, 3.f}, {0.f, 0.f, 2.f}});
  const InsertStats s =
      map.insert(cloud, Eigen::Isometry3d::Identity(), SensorModel::autoFromCloud());
  EXPECT_EQ(s.sensor.type, SensorType::kPinhole);
  EXPECT_TRUE(s.sensor.forward_S.isApprox(Eigen::Vector3d::UnitZ()));
  EXPECT_GT(s.sensor.hfov_rad, 0.0);
  EXPECT_GE(s.sensor.max_range_m, 3.0);  // no limit given: the farthest point
  EXPECT_NO_THROW(s.sensor.validate());
}

TEST(InsertStatsSensor, AnExplicitModelComesBackAsGiven) {
  Map map(
      cpuParams(-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()));
  const SensorModel lidar = SensorModel::spinningLidar(-0.3, 0.3, 0.0, 20.0);
  const InsertStats s =
      map.insert(test::cloudOf({{2.f, 0.f, 0.f}}), Eigen::Isometry3d::Identity(), lidar);
  EXPECT_EQ(s.sensor.type, SensorType::kSpinningLidar);
  EXPECT_EQ(s.sensor.elevation_max_rad, 0.3);
  EXPECT_EQ(s.sensor.max_range_m, 20.0);
}

}  // namespace
}  // namespace fragg
