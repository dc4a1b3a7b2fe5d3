// Simulated sensors and recordings: NaN exactly where there is no return, noise and dropout
// statistics, depth camera geometry, determinism of the written datasets and the map built
// from them, odometry drift.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <string>

#include "fragg_map/io/dataset.h"
#include "fragg_map/map.h"
#include "fragg_map/sim/dataset_writers.h"
#include "fragg_map/sim/depth_camera.h"
#include "fragg_map/sim/lidar_sensor.h"
#include "fragg_map/sim/trajectory.h"
#include "sim_test_util.h"

namespace fragg::sim {
namespace {

using geometry::MeshBvh;
using geometry::TriangleMesh;

constexpr double kSensorHeightM = 2.0;

Eigen::Isometry3d at(double x, double y, double z, double yaw = 0.0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, y, z);
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).matrix();
  return T;
}

LidarSpec smallLidar() {
  LidarSpec s;
  s.beams = 16;
  s.azimuth_steps = 90;
  s.elevation_min_deg = -15;
  s.elevation_max_deg = 15;
  s.max_range_m = 30;
  return s;
}

TEST(SimLidar, OrganisedCloudHasNanExactlyWhereThereIsNoReturn) {
  const MeshBvh ground(test::flatGround(100));  // open scene: ground only
  const LidarSpec spec = smallLidar();
  const PointCloud c = simulateLidar(ground, spec, at(1, 2, kSensorHeightM, 0.3), 1, 0);
  ASSERT_EQ(c.width, 90u);
  ASSERT_EQ(c.height, 16u);
  ASSERT_TRUE(c.organised());
  for (int beam = 0; beam < spec.beams; ++beam) {
    const double el = (15.0 - 30.0 * beam / 15) * M_PI / 180.0;
    const double range = el < 0 ? kSensorHeightM / std::sin(-el) : INFINITY;
    const bool expect_return = range < spec.max_range_m;
    for (int col = 0; col < spec.azimuth_steps; ++col) {
      const Eigen::Vector3f& p = c.points_S[beam * spec.azimuth_steps + col];
      ASSERT_EQ(p.allFinite(), expect_return) << "beam " << beam << " elevation " << el;
      if (!expect_return) {
        EXPECT_TRUE(std::isnan(p.x()) && std::isnan(p.y()) && std::isnan(p.z()));
        continue;
      }
      EXPECT_NEAR(p.norm(), range, 1e-4 * range);
      EXPECT_NEAR(p.z(), -kSensorHeightM, 1e-4);  // on the ground, in the sensor frame
    }
  }
}

TEST(SimLidar, RangeNoiseAndDropoutHaveTheirConfiguredStatistics) {
  const MeshBvh ground(test::flatGround(100));
  LidarSpec spec = smallLidar();
  spec.azimuth_steps = 2000;
  spec.elevation_max_deg = -10;  // every beam hits the ground within 12 m
  spec.range_noise_m = 0.05;
  spec.dropout = 0.1;
  const PointCloud c = simulateLidar(ground, spec, at(0, 0, kSensorHeightM), 3, 0);
  double sum = 0, sum2 = 0;
  size_t returns = 0;
  for (int beam = 0; beam < spec.beams; ++beam) {
    const double el = (-10.0 - 5.0 * beam / 15) * M_PI / 180.0;
    const double range = kSensorHeightM / std::sin(-el);
    for (int col = 0; col < spec.azimuth_steps; ++col) {
      const Eigen::Vector3f& p = c.points_S[beam * spec.azimuth_steps + col];
      if (!p.allFinite()) continue;
      const double e = p.norm() - range;
      sum += e;
      sum2 += e * e;
      ++returns;
    }
  }
  const double n = double(c.size());
  EXPECT_NEAR(1.0 - returns / n, 0.1, 0.01);  // 32,000 rays: sigma of the fraction ~0.0017
  const double mean = sum / returns, sd = std::sqrt(sum2 / returns - mean * mean);
  EXPECT_NEAR(mean, 0.0, 0.003);
  EXPECT_NEAR(sd, 0.05, 0.0025);
}

TEST(SimDepthCamera, DepthIsTheDistanceAlongTheOpticalAxis) {
  TriangleMesh m;
  m.appendSolid(makeBox({5, -3, -2}, {6, 3, 2}));  // a wall 5 m ahead, 6 x 4 m
  const MeshBvh bvh(m);
  DepthCameraSpec spec;
  spec.width = 64;
  spec.height = 48;
  spec.hfov_deg = 90;
  spec.max_range_m = 10;
  Eigen::Isometry3d T_map_camera = Eigen::Isometry3d::Identity();
  T_map_camera.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;  // optical z = map x
  const PointCloud c = simulateDepthCamera(bvh, spec, T_map_camera, 1, 0);
  ASSERT_TRUE(c.organised());
  const DepthIntrinsics k = spec.intrinsics();
  size_t nan = 0;
  for (int v = 0; v < spec.height; ++v)
    for (int u = 0; u < spec.width; ++u) {
      const Eigen::Vector3f& p = c.points_S[v * spec.width + u];
      // The pixel ray meets the plane x = 5 at lateral offsets (u - cx) / fx * 5.
      const double lateral = std::abs((u - k.cx) / k.fx * 5),
                   vertical = std::abs((v - k.cy) / k.fy * 5);
      const bool on_wall = lateral < 3 && vertical < 2;
      if (!on_wall) {
        EXPECT_FALSE(p.allFinite());
        ++nan;
        continue;
      }
      ASSERT_TRUE(p.allFinite());
      EXPECT_NEAR(p.z(), 5.0, 1e-4);
    }
  EXPECT_GT(nan, 0u);  // the field of view is wider than the wall
}

// Records a few frames of a small scene into a KITTI folder and a depth folder.
void record(const std::string& dir, uint64_t seed) {
  TriangleMesh m = test::flatGround(60);
  m.appendSolid(makeBox({4, -2, -1}, {6, 2, 3}));
  m.appendSolid(makeCylinder({-3, 3, -1}, {-3, 3, 4}, 0.4));
  const MeshBvh bvh(m);
  LidarSpec lidar = smallLidar();
  lidar.range_noise_m = 0.02;
  lidar.dropout = 0.05;
  DepthCameraSpec cam;
  cam.width = 32;
  cam.height = 24;
  cam.noise_m = 0.01;
  TrajectorySpec traj;
  traj.waypoints_m = {{-2, -1, 0}, {2, 1, 0}};
  traj.rate_hz = 5;
  DriftSpec drift;
  drift.drift_m_per_m = 0.02;
  drift.drift_rad_per_m = 0.01;
  const auto poses = sampleTrajectory(
      traj, [](double, double) { return 0.0; }, drift, seed);
  Eigen::Isometry3d T_base_lidar = at(0, 0, kSensorHeightM);
  Eigen::Isometry3d T_base_cam = at(0, 0, 1);
  T_base_cam.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  KittiFolderWriter kitti(dir + "/kitti", true);
  DepthFolderWriter depth(dir + "/depth", cam.intrinsics());
  for (size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Isometry3d T_l = poses[i].T_map_base * T_base_lidar;
    const Eigen::Isometry3d T_c = poses[i].T_map_base * T_base_cam;
    kitti.add(simulateLidar(bvh, lidar, T_l, seed, i), T_l, poses[i].T_odom_base * T_base_lidar,
              poses[i].stamp_s);
    depth.add(simulateDepthCamera(bvh, cam, T_c, seed, i), T_c, poses[i].T_odom_base * T_base_cam,
              poses[i].stamp_s);
  }
  kitti.finish();
  depth.finish();
}

// Every file under `dir`, relative path -> bytes.
std::map<std::string, std::string> filesUnder(const std::string& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
    if (e.is_regular_file())
      out[std::filesystem::relative(e.path(), dir).string()] = test::readBytes(e.path().string());
  return out;
}

std::string mapBytes(const std::string& input, const std::string& out_path) {
  MapParams p;
  p.resolution_m = 0.1;
  p.backend = Backend::kCpu;
  Map map(p);
  auto source = openDataset(input);
  Scan s;
  while (source->next(s)) map.insert(s.cloud, s.T_map_sensor, SensorModel::autoFromCloud());
  map.save(out_path);
  return test::readBytes(out_path);
}

TEST(SimRecording, SameSeedSameBytesDifferentSeedDifferentScans) {
  const std::string dir = test::testDir();
  record(dir + "/a", 7);
  record(dir + "/b", 7);
  record(dir + "/c", 8);
  const auto a = filesUnder(dir + "/a"), b = filesUnder(dir + "/b"), c = filesUnder(dir + "/c");
  ASSERT_GT(a.size(), 10u);
  EXPECT_EQ(a, b);
  EXPECT_NE(a.at("kitti/velodyne/000003.bin"), c.at("kitti/velodyne/000003.bin"));
  EXPECT_NE(a.at("kitti/poses_odom.txt"), c.at("kitti/poses_odom.txt"));  // drift is seeded
  EXPECT_EQ(a.at("kitti/poses.txt"), c.at("kitti/poses.txt"));            // ground truth is not
  // The maps built from them: same seed, same bytes.
  EXPECT_EQ(mapBytes(dir + "/a/kitti", dir + "/a.fgm"), mapBytes(dir + "/b/kitti", dir + "/b.fgm"));
  EXPECT_NE(mapBytes(dir + "/a/kitti", dir + "/a.fgm"), mapBytes(dir + "/c/kitti", dir + "/c.fgm"));
}

TEST(SimRecording, DatasetsReadBackThroughTheCoreReaders) {
  const std::string dir = test::testDir();
  record(dir, 5);
  // KITTI: ground-truth sensor poses, valid returns only.
  auto kitti = openDataset(dir + "/kitti");
  ASSERT_EQ(kitti->size(), std::optional<size_t>(23));  // 4.47 m at 0.2 m steps (+1)
  Scan s;
  ASSERT_TRUE(kitti->next(s));
  EXPECT_NEAR(s.T_map_sensor.translation().z(), kSensorHeightM, 1e-9);
  for (const auto& p : s.cloud.points_S) ASSERT_TRUE(p.allFinite());
  // Organised PCDs keep the NaNs and the beam x azimuth layout.
  auto organised = openDataset(dir + "/kitti/organised");
  ASSERT_TRUE(organised->next(s));
  EXPECT_EQ(s.cloud.width, 90u);
  EXPECT_EQ(s.cloud.height, 16u);
  size_t nan = 0;
  for (const auto& p : s.cloud.points_S) nan += !p.allFinite();
  EXPECT_GT(nan, 0u);
  // Depth folder: organised optical-frame clouds.
  auto depth = openDataset(dir + "/depth");
  ASSERT_TRUE(depth->next(s));
  EXPECT_EQ(s.cloud.width, 32u);
  EXPECT_EQ(s.cloud.height, 24u);
  EXPECT_NEAR(s.T_map_sensor.translation().z(), 1.0, 1e-6);
}

TEST(SimTrajectory, OdometryDriftsAsConfiguredAndGroundTruthFollowsTheWaypoints) {
  TrajectorySpec traj;
  traj.waypoints_m = {{0, 0, 0}, {50, 0, 0}, {50, 50, 0}};
  traj.speed_mps = 2;
  traj.rate_hz = 4;
  const auto flat = [](double, double) { return 1.5; };
  const auto exact = sampleTrajectory(traj, flat, DriftSpec{}, 1);
  ASSERT_EQ(exact.size(), 201u);  // 100 m at 0.5 m steps
  for (const PoseSample& p : exact) {
    EXPECT_TRUE(p.T_odom_base.isApprox(p.T_map_base, 1e-9));
    EXPECT_NEAR(p.T_map_base.translation().z(), 0.0, 1e-12);  // follow_ground is off
  }
  EXPECT_NEAR(exact[50].T_map_base.translation().x(), 25.0, 1e-9);
  EXPECT_NEAR(exact[50].stamp_s, 12.5, 1e-12);
  DriftSpec drift;
  drift.drift_rad_per_m = 0.002;
  drift.drift_m_per_m = 0.01;
  traj.follow_ground = true;
  const auto drifting = sampleTrajectory(traj, flat, drift, 1);
  const double err_mid =
      (drifting[100].T_odom_base.translation() - drifting[100].T_map_base.translation()).norm();
  const double err_end =
      (drifting.back().T_odom_base.translation() - drifting.back().T_map_base.translation()).norm();
  EXPECT_GT(err_mid, 0.3);  // 50 m with 1 % translation and 0.1 rad heading error
  EXPECT_GT(err_end, err_mid);
  EXPECT_NEAR(drifting[0].T_map_base.translation().z(), 1.5, 1e-12);
}

}  // namespace
}  // namespace fragg::sim
