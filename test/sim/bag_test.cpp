// The simulator's bag read back by the core's bag reader: organised clouds with their NaNs,
// sensor poses from map -> odom -> base_link (drifting odometry) -> sensor.
#include <gtest/gtest.h>

#include <fstream>

#include "fragg_map/io/rosbag_source.h"
#include "fragg_map/sim/bag_writer.h"
#include "fragg_map/sim/lidar_sensor.h"
#include "sim_test_util.h"

namespace fragg::sim {
namespace {

using geometry::MeshBvh;

TEST(SimBag, CloudsAndTfReadBackThroughTheCoreBagReader) {
  const std::string path = test::testDir() + "/sim.bag";
  const MeshBvh ground(test::flatGround(50));
  LidarSpec lidar;
  lidar.beams = 16;
  lidar.azimuth_steps = 120;
  TrajectorySpec traj;
  traj.waypoints_m = {{0, 0, 0}, {10, 5, 0}};
  traj.rate_hz = 2;
  DriftSpec drift;
  drift.drift_m_per_m = 0.05;
  drift.drift_rad_per_m = 0.02;
  const auto poses = sampleTrajectory(
      traj, [](double, double) { return 0.0; }, drift, 4);
  ASSERT_GT(poses.size(), 5u);
  Eigen::Isometry3d T_base_sensor = Eigen::Isometry3d::Identity();
  T_base_sensor.translation() = Eigen::Vector3d(0.1, 0, 1.8);
  std::vector<size_t> nans;
  {
    SimBagWriter bag(path, BagNames(), T_base_sensor, true);
    for (size_t i = 0; i < poses.size(); ++i) {
      const PointCloud c = simulateLidar(ground, lidar, poses[i].T_map_base * T_base_sensor, 4, i);
      size_t n = 0;
      for (const auto& p : c.points_S) n += !p.allFinite();
      nans.push_back(n);
      bag.add(c, poses[i]);
    }
    bag.finish();
  }
  DatasetOptions options;
  options.topic = "/points";
  options.frame = "map";
  auto source = openRosbag(path, options);
  Scan s;
  size_t i = 0;
  while (source->next(s)) {
    ASSERT_LT(i, poses.size());
    EXPECT_EQ(s.cloud.width, 120u);
    EXPECT_EQ(s.cloud.height, 16u);
    size_t n = 0;
    for (const auto& p : s.cloud.points_S) n += !p.allFinite();
    EXPECT_EQ(n, nans[i]);
    EXPECT_GT(n, 0u);
    // The bag's tf gives the drifting odometry's sensor pose, not the ground truth.
    const Eigen::Isometry3d expected = poses[i].T_odom_base * T_base_sensor;
    EXPECT_TRUE(s.T_map_sensor.isApprox(expected, 1e-6)) << "frame " << i;
    if (i > 2) {
      EXPECT_FALSE(s.T_map_sensor.isApprox(poses[i].T_map_base * T_base_sensor, 1e-4));
    }
    ++i;
  }
  EXPECT_EQ(i, poses.size());
  EXPECT_EQ(source->skipped(), 0u);
}

// The smoke workload the build generates (cmake/sim_workloads.cmake): small, complete, placed.
TEST(SimBag, SmokeWorkloadBagIsSmallAndReadable) {
  std::ifstream f(FRAGG_SMOKE_BAG, std::ios::binary | std::ios::ate);
  ASSERT_TRUE(f.good()) << FRAGG_SMOKE_BAG;
  EXPECT_LT(static_cast<long>(f.tellg()), 2L * 1024 * 1024);
  registerRosbagReader();
  auto source = openDataset(FRAGG_SMOKE_BAG);  // the only PointCloud2 topic, frame "map"
  Scan s;
  size_t scans = 0;
  while (source->next(s)) {
    EXPECT_EQ(s.cloud.width, 360u);
    EXPECT_EQ(s.cloud.height, 16u);
    EXPECT_GT(s.T_map_sensor.translation().z(), 1.0);  // 1.8 m above the sloped ground
    ++scans;
  }
  EXPECT_EQ(scans, 10u);
}

}  // namespace
}  // namespace fragg::sim
