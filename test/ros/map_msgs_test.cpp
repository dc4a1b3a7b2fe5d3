// Map -> PointCloud2 of occupied centres (round trip through cloudFromMsg) and map ->
// OccupancyGrid between two heights.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "fragg_map/errors.h"
#include "fragg_map/ros/cloud_from_msg.h"
#include "fragg_map/ros/occupied_cloud.h"
#include "fragg_map/ros/projected_map.h"
#include "map_fixtures.h"

namespace {

const ros::Time kStamp(5, 0);

bool lexLess(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
}

TEST(OccupiedCloud, RoundTripGivesTheOccupiedCentres) {
  fragg::Map map(fragg::ros::test::cpuParams(0.05));
  fragg::ros::test::insertWall(map, Eigen::Vector3d(0.5, -0.2, 0.3), 2.0);
  const sensor_msgs::PointCloud2 msg = fragg::ros::occupiedCloud(map, "map", kStamp);
  EXPECT_EQ(msg.header.frame_id, "map");
  EXPECT_EQ(msg.header.stamp, kStamp);
  EXPECT_EQ(msg.height, 1u);
  EXPECT_EQ(msg.point_step, 12u);
  fragg::ros::CloudLayout layout{};
  const fragg::PointCloud back = fragg::ros::cloudFromMsg(msg, &layout);
  EXPECT_EQ(layout, fragg::ros::CloudLayout::kPackedFloat32);
  auto want = fragg::ros::test::centresIn(map, fragg::CellState::kOccupied);
  std::vector<Eigen::Vector3d> got;
  for (const auto& p : back.points_S) got.push_back(p.cast<double>());
  ASSERT_EQ(got.size(), want.size());
  std::sort(want.begin(), want.end(), lexLess);
  std::sort(got.begin(), got.end(), lexLess);
  for (size_t i = 0; i < want.size(); ++i) {
    EXPECT_LT((want[i] - got[i]).norm(), 1e-5) << i;
    EXPECT_EQ(map.keyOf(got[i]), map.keyOf(want[i]));
  }
}

TEST(OccupiedCloud, EmptyMapGivesAnEmptyCloud) {
  fragg::Map map(fragg::ros::test::cpuParams());
  const sensor_msgs::PointCloud2 msg = fragg::ros::occupiedCloud(map, "odom", kStamp);
  EXPECT_EQ(msg.width, 0u);
  EXPECT_TRUE(msg.data.empty());
  EXPECT_EQ(msg.fields.size(), 3u);
}

TEST(ProjectedMap, ColumnsBetweenMinAndMaxZ) {
  // Resolution 0.1 m: voxel z key k has its centre at (k + 0.5) * 0.1 m.
  fragg::Map map(fragg::ros::test::cpuParams(0.1));
  using S = fragg::CellState;
  fragg::ros::test::setCell(map, {0, 0, 5}, S::kOccupied);   // z 0.55: inside [0, 1]
  fragg::ros::test::setCell(map, {1, 0, 5}, S::kFree);       // free column
  fragg::ros::test::setCell(map, {2, 0, 20}, S::kOccupied);  // z 2.05: above -> unknown
  fragg::ros::test::setCell(map, {3, 0, 2}, S::kFree);       // free below occupied: occupied
  fragg::ros::test::setCell(map, {3, 0, 3}, S::kOccupied);
  fragg::ros::test::setCell(map, {-2, 4, 1}, S::kFree);  // extends the bounds to x -2, y 4
  const nav_msgs::OccupancyGrid grid = fragg::ros::projectedMap(map, 0.0, 1.0, "map", kStamp);
  EXPECT_EQ(grid.header.frame_id, "map");
  EXPECT_FLOAT_EQ(grid.info.resolution, 0.1f);
  ASSERT_EQ(grid.info.width, 6u);   // x keys -2 .. 3
  ASSERT_EQ(grid.info.height, 5u);  // y keys 0 .. 4
  EXPECT_DOUBLE_EQ(grid.info.origin.position.x, -0.2);
  EXPECT_DOUBLE_EQ(grid.info.origin.position.y, 0.0);
  ASSERT_EQ(grid.data.size(), 30u);
  auto at = [&](int x, int y) { return grid.data[(y - 0) * 6 + (x + 2)]; };
  EXPECT_EQ(at(0, 0), 100);
  EXPECT_EQ(at(1, 0), 0);
  EXPECT_EQ(at(2, 0), -1);
  EXPECT_EQ(at(3, 0), 100);
  EXPECT_EQ(at(-2, 4), 0);
  EXPECT_EQ(at(-1, 2), -1);
  size_t known = 0;
  for (int8_t v : grid.data) known += v != -1;
  EXPECT_EQ(known, 4u);
  // Raising the ceiling brings the high cell in.
  const nav_msgs::OccupancyGrid tall = fragg::ros::projectedMap(map, 0.0, 3.0, "map", kStamp);
  EXPECT_EQ(tall.data[0 * 6 + 4], 100);
}

TEST(ProjectedMap, EmptyMapAndBadHeights) {
  fragg::Map map(fragg::ros::test::cpuParams());
  const nav_msgs::OccupancyGrid grid = fragg::ros::projectedMap(map, 0.0, 1.0, "map", kStamp);
  EXPECT_EQ(grid.info.width, 0u);
  EXPECT_TRUE(grid.data.empty());
  EXPECT_THROW(fragg::ros::projectedMap(map, 1.0, 0.0, "map", kStamp), fragg::InvalidArgument);
  EXPECT_THROW(fragg::ros::projectedMap(map, NAN, 0.0, "map", kStamp), fragg::InvalidArgument);
}

}  // namespace

#include "fragg_map/ros/frustum_marker.h"

namespace {

TEST(FrustumMarker, PinholePyramidInTheMapFrame) {
  const fragg::SensorModel cam = fragg::SensorModel::pinhole(M_PI / 2, M_PI / 2, 0.0, 2.0);
  Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
  T_map_sensor.translation() = Eigen::Vector3d(1.0, 2.0, 3.0);
  const visualization_msgs::Marker m = fragg::ros::frustumMarker(cam, T_map_sensor, "map", kStamp);
  EXPECT_EQ(m.type, visualization_msgs::Marker::LINE_LIST);
  ASSERT_EQ(m.points.size(), 16u);  // 4 edges from the apex + 4 far-plane edges
  for (size_t i = 0; i < m.points.size(); i += 2) {
    const Eigen::Vector3d a(m.points[i].x, m.points[i].y, m.points[i].z);
    const Eigen::Vector3d b(m.points[i + 1].x, m.points[i + 1].y, m.points[i + 1].z);
    if (i % 4 == 0) {
      EXPECT_LT((a - T_map_sensor.translation()).norm(), 1e-12);  // from the apex
      EXPECT_NEAR((b - a).norm(), 2.0, 1e-9);                     // to max range
      EXPECT_GT(b.z(), 3.0);                                      // optical axis is +z
    }
  }
}

TEST(FrustumMarker, LidarRimsAtMaxRangeAndBadModels) {
  const fragg::SensorModel lidar = fragg::SensorModel::spinningLidar(-0.3, 0.2, 0.0, 10.0);
  const visualization_msgs::Marker m =
      fragg::ros::frustumMarker(lidar, Eigen::Isometry3d::Identity(), "map", kStamp, 8);
  ASSERT_FALSE(m.points.empty());
  for (const auto& p : m.points) {
    const double r = Eigen::Vector3d(p.x, p.y, p.z).norm();
    EXPECT_TRUE(r < 1e-12 || std::abs(r - 10.0) < 1e-9) << r;
  }
  EXPECT_THROW(fragg::ros::frustumMarker(fragg::SensorModel::autoFromCloud(0.0, 5.0),
                                         Eigen::Isometry3d::Identity(), "map", kStamp),
               fragg::InvalidArgument);
  EXPECT_THROW(fragg::ros::frustumMarker(fragg::SensorModel::spinningLidar(-0.3, 0.2, 0.0, -1.0),
                                         Eigen::Isometry3d::Identity(), "map", kStamp),
               fragg::InvalidArgument);
}

}  // namespace
