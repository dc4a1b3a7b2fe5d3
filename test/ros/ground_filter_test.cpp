// filter_ground's segmentation (fragg_map/ros/ground_filter.h) on synthetic scenes seen from a
// sensor 1 m above the base frame's origin.
#include "fragg_map/ros/ground_filter.h"

#include <gtest/gtest.h>

#include <random>

#include "fragg_map/map.h"

namespace fragg::ros {
namespace {

enum class Part : uint8_t { kFloor, kTable, kWall };

struct Scene {
  PointCloud cloud;  ///< sensor frame
  std::vector<Part> part;
};

constexpr double kSensorHeight_m = 1.0;

Eigen::Isometry3d sensorAboveBase() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation().z() = kSensorHeight_m;
  return T;
}

/// Base-frame parts, stored in the sensor frame: a floor (z = 0, +-1 cm noise) of
/// `floor_side` x `floor_side` points, a table top at 0.75 m (30 x 30, a cell centre at 10 cm) and
/// a wall at x = 3 m.
Scene scene(int floor_side, bool table = true) {
  Scene s;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> noise(-0.01f, 0.01f);
  auto add = [&](float x, float y, float z, Part p) {
    s.cloud.points_S.emplace_back(x, y, static_cast<float>(z - kSensorHeight_m));
    s.part.push_back(p);
  };
  for (int i = 0; i < floor_side; ++i)
    for (int j = 0; j < floor_side; ++j)
      add(0.5f + 0.1f * i, -1.0f + 0.1f * j, noise(rng), Part::kFloor);
  if (table)
    for (int i = 0; i < 30; ++i)
      for (int j = 0; j < 30; ++j) add(1.0f + 0.02f * i, 0.5f + 0.02f * j, 0.75f, Part::kTable);
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 15; ++j) add(3.0f, -1.0f + 0.1f * i, 0.1f + 0.1f * j, Part::kWall);
  return s;
}

size_t flaggedOf(const Scene& s, Part p) {
  size_t n = 0;
  for (size_t i = 0; i < s.part.size(); ++i) n += s.part[i] == p && s.cloud.freeOnly(i);
  return n;
}

TEST(GroundFilterTest, FloorIsGroundTableAndWallAreNot) {
  // The table (900 points) outnumbers the floor (400): RANSAC finds it first, it lies 0.75 m
  // above z = 0, so it is set aside and the floor is found next.
  Scene s = scene(20);
  const GroundSplit split = markGroundPoints(sensorAboveBase(), GroundFilterParams(), &s.cloud);
  EXPECT_TRUE(split.plane_found);
  EXPECT_GE(split.other_planes, 1u);
  EXPECT_EQ(split.points, s.cloud.size());
  ASSERT_EQ(s.cloud.free_only.size(), s.cloud.size());
  EXPECT_EQ(flaggedOf(s, Part::kFloor), 400u);
  EXPECT_EQ(flaggedOf(s, Part::kTable), 0u);
  EXPECT_EQ(flaggedOf(s, Part::kWall), 0u);
  EXPECT_EQ(split.ground, 400u);
}

TEST(GroundFilterTest, TheBaseFramePlacesTheGround) {
  // Seen in the sensor frame (identity), the floor is 1 m below z = 0 and the table 0.25 m: both
  // are set aside, no plane is ground, and the fallback band takes the one wall row at z = 0
  // of the sensor frame (1 m above the floor), not the floor.
  Scene s = scene(20);
  const GroundSplit split =
      markGroundPoints(Eigen::Isometry3d::Identity(), GroundFilterParams(), &s.cloud);
  EXPECT_FALSE(split.plane_found);
  EXPECT_GE(split.other_planes, 2u);  // the table, then the floor
  EXPECT_EQ(flaggedOf(s, Part::kFloor), 0u);
  EXPECT_EQ(flaggedOf(s, Part::kTable), 0u);
  EXPECT_EQ(flaggedOf(s, Part::kWall), 20u);
  EXPECT_EQ(split.ground, 20u);
}

TEST(GroundFilterTest, NoGroundPlaneFallsBackToTheHeightBand) {
  // No floor: the table is set aside, the wall is no horizontal plane; its lowest row (z 0.1)
  // is outside plane_distance 0.07, so nothing is ground; with plane_distance 0.12 that row is.
  Scene s = scene(0);
  GroundFilterParams params;
  GroundSplit split = markGroundPoints(sensorAboveBase(), params, &s.cloud);
  EXPECT_FALSE(split.plane_found);
  EXPECT_EQ(split.ground, 0u);
  Scene t = scene(0);
  params.plane_distance_m = 0.12;
  split = markGroundPoints(sensorAboveBase(), params, &t.cloud);
  EXPECT_FALSE(split.plane_found);  // every 3 wall points span the (vertical) wall
  EXPECT_EQ(split.ground, 20u);
  EXPECT_EQ(flaggedOf(t, Part::kWall), 20u);
  EXPECT_EQ(flaggedOf(t, Part::kTable), 0u);
}

TEST(GroundFilterTest, SmallCloudsAndInvalidPointsAreLeftAlone) {
  PointCloud small;
  for (int i = 0; i < 49; ++i) small.points_S.emplace_back(0.1f * i, 0.f, -1.f);
  const GroundSplit split = markGroundPoints(sensorAboveBase(), GroundFilterParams(), &small);
  EXPECT_EQ(split.points, 49u);
  EXPECT_EQ(split.ground, 0u);
  EXPECT_TRUE(small.free_only.empty());

  Scene s = scene(20);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  s.cloud.points_S[0] = Eigen::Vector3f(nan, 0.f, 0.f);  // a floor point lost
  s.cloud.points_S[1] = Eigen::Vector3f::Zero();         // and a "no return"
  const GroundSplit with_invalid =
      markGroundPoints(sensorAboveBase(), GroundFilterParams(), &s.cloud);
  EXPECT_EQ(with_invalid.points, s.cloud.size() - 2);
  EXPECT_FALSE(s.cloud.freeOnly(0));
  EXPECT_FALSE(s.cloud.freeOnly(1));
  EXPECT_EQ(flaggedOf(s, Part::kFloor), 398u);
}

TEST(GroundFilterTest, MarkedFloorIsFreeInTheMapAndTheTableOccupied) {
  Scene s = scene(20);
  markGroundPoints(sensorAboveBase(), GroundFilterParams(), &s.cloud);
  MapParams params;
  params.resolution_m = 0.1;
  Map map(params);
  map.insert(s.cloud, sensorAboveBase(), SensorModel::autoFromCloud());
  size_t floor_occupied = 0, table_occupied = 0;
  for (size_t i = 0; i < s.cloud.size(); ++i) {
    const Eigen::Vector3d p_map = sensorAboveBase() * s.cloud.points_S[i].cast<double>();
    const bool occupied = map.query(p_map) == CellState::kOccupied;
    floor_occupied += s.part[i] == Part::kFloor && occupied;
    table_occupied += s.part[i] == Part::kTable && occupied;
  }
  EXPECT_EQ(floor_occupied, 0u);
  EXPECT_EQ(table_occupied, 900u);
}

}  // namespace
}  // namespace fragg::ros
