// W4, the long drive (config/scenes/campus_long.json, config/workloads/w4_long_drive.args),
// checked without generating it (1.5 GB, bench time only): the scene is the campus laid out
// four times, the loop is closed, at least 1 km long with at least 500 scans, and keeps the
// sensor out of every solid; one scan of a coarse LiDAR sees the same campus in every tile.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/sim/lidar_sensor.h"
#include "fragg_map/sim/scene.h"

namespace fragg::sim {
namespace {

const std::string kScenes = FRAGG_SCENES_DIR;
const std::string kArgs = FRAGG_WORKLOADS_CONFIG_DIR "/w4_long_drive.args";

// The value after `flag` in the workload's arguments ("" when absent).
std::string argOf(const std::string& flag) {
  std::ifstream in(kArgs);
  EXPECT_TRUE(in.good()) << kArgs;
  std::string line, word;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    while (words >> word)
      if (word == flag && words >> word) return word;
  }
  return "";
}

TEST(SimLongDrive, LoopIsClosedLongerThan1kmWithAtLeast500Scans) {
  const Scene scene = loadScene(kScenes + "/campus_long.json");
  ASSERT_EQ(argOf("--trajectory"), "long_loop");
  ASSERT_EQ(scene.trajectories.count("long_loop"), 1u);
  const Terrain& t = scene.terrain;
  const std::vector<PoseSample> poses = sampleTrajectory(
      scene.trajectories.at("long_loop"), [&t](double x, double y) { return t.heightAt(x, y); },
      DriftSpec(), 505);
  double length_m = 0;
  for (size_t i = 1; i < poses.size(); ++i)
    length_m += (poses[i].T_map_base.translation() - poses[i - 1].T_map_base.translation())
                    .head<2>()
                    .norm();
  EXPECT_GE(poses.size(), 500u);
  EXPECT_GE(length_m, 1000.0);
  EXPECT_LT((poses.back().T_map_base.translation() - poses.front().T_map_base.translation()).norm(),
            1e-9);  // back where it started: a loop

  // The sensor (W1's mount, 1.8 m above the base) and the base stay out of every solid.
  const geometry::MeshBvh bvh(scene.mesh);
  for (size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Vector3d p = poses[i].T_map_base.translation();
    ASSERT_FALSE(bvh.inside((p + Eigen::Vector3d(0, 0, 1.8)).cast<float>())) << "pose " << i;
    ASSERT_FALSE(bvh.inside((p + Eigen::Vector3d(0, 0, 0.2)).cast<float>())) << "pose " << i;
  }
}

TEST(SimLongDrive, SceneIsTheCampusFourTimesAlongX) {
  const Scene campus = loadScene(kScenes + "/campus.json");
  const Scene w4 = loadScene(kScenes + "/campus_long.json");
  EXPECT_EQ(w4.mesh.solid_count - 1, 4 * (campus.mesh.solid_count - 1));  // one ground each
  EXPECT_EQ(w4.terrain.x0_m, campus.terrain.x0_m);
  EXPECT_EQ(w4.terrain.x1_m, campus.terrain.x1_m + 3 * 150);
  EXPECT_EQ(w4.terrain.y1_m, campus.terrain.y1_m);
  // A coarse scan from the same place in each tile, height-corrected for the slope, sees the
  // same ranges as in the campus within the terrain's change of height (the ground rises 3 m a
  // tile along x; buildings stand on it).
  LidarSpec lidar;
  lidar.beams = 8;
  lidar.azimuth_steps = 90;
  lidar.max_range_m = 30;
  const geometry::MeshBvh bvh_campus(campus.mesh), bvh_w4(w4.mesh);
  auto scan = [&](const geometry::MeshBvh& bvh, const Terrain& t, double x) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(x, 0, t.heightAt(x, 0) + 1.8);
    return simulateLidar(bvh, lidar, T, 1, 0);
  };
  const PointCloud ref = scan(bvh_campus, campus.terrain, 0.0);
  for (int tile = 0; tile < 4; ++tile) {
    SCOPED_TRACE(tile);
    const PointCloud c = scan(bvh_w4, w4.terrain, 150.0 * tile);
    ASSERT_EQ(c.size(), ref.size());
    size_t same = 0, returns = 0;
    for (size_t i = 0; i < c.size(); ++i) {
      const bool a = c.points_S[i].allFinite(), b = ref.points_S[i].allFinite();
      returns += b;
      if (a && b && std::abs(c.points_S[i].norm() - ref.points_S[i].norm()) < 0.05f) ++same;
    }
    EXPECT_GT(returns, c.size() / 2);
    EXPECT_GE(same, returns * 9 / 10);
  }
}

}  // namespace
}  // namespace fragg::sim
