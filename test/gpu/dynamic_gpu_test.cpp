// Dynamic-aware mapping (MapParams::dynamic, issue 37) on the CUDA backend against the CPU
// backend: the labelled room of test/core/dynamic_scene.h (a person who stands, leaves, walks
// across and stands again) under both void-space rules and both radii, and a slice of W6 (the
// office with people walking, config/scenes/office_people.json, a depth camera) with a pool
// small enough to evict and upload blocks again. After every scan the maps are byte-identical
// (every block's cells and state masks), and the points classified dynamic are the same points.
// Also a slice of W5 (campus street with movers, its 32 x 1024 LiDAR with dropout) as an
// unorganised cloud with the LiDAR's beam table and clear_no_return_rays: the no-return beams
// cleared, maps byte-identical. Skipped without a device.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <iterator>
#include <string>
#include <vector>

#include "../core/dynamic_scene.h"
#include "../core/same_map.h"
#include "../core/state_masks_check.h"
#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/map.h"
#include "fragg_map/sim/depth_camera.h"
#include "fragg_map/sim/lidar_sensor.h"
#include "fragg_map/sim/scene.h"
#include "fragg_map/sim/trajectory.h"
#include "gpu_test_util.h"

namespace fragg::test {
namespace {

/// The CUDA map (its host view, after the write-back) equal to the CPU map cell for cell and
/// mask for mask.
void expectSameMaps(const Map& cpu, const Map& gpu, const std::string& what) {
  ASSERT_STREQ(gpu.backendName(), "cuda") << gpu.backendReason();
  expectSameMap(cpu, gpu, what.c_str());
  std::string first;
  EXPECT_EQ(blocksWithOtherMasks(gpu, cpu, &first), 0u) << what << ": " << first;
  EXPECT_EQ(blocksWithStaleMasks(gpu, &first), 0u) << what << " (cuda): " << first;
}

/// Both maps' dynamic points of the last scan: the same points, in the same (cloud) order.
void expectSameDynamicPoints(const Map& cpu, const Map& gpu, const std::string& what) {
  const std::vector<Eigen::Vector3f>& a = cpu.lastDynamicPoints_S();
  const std::vector<Eigen::Vector3f>& b = gpu.lastDynamicPoints_S();
  ASSERT_EQ(a.size(), b.size()) << what;
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i], b[i]) << what << ", point " << i;
}

/// The labelled room through both backends under `rule`, radius `radius`: byte-identical after
/// every scan, the same dynamic points, and the person's later stand is found dynamic.
void roomOnBothBackends(VoidSpaceRule rule, int radius, bool warp_per_slot) {
  MapParams p = dynamicSceneParams(true, rule, radius);
  Map cpu(p);
  p.backend = Backend::kCuda;
  p.cuda.warp_per_slot_apply = warp_per_slot;
  Map gpu(p);
  const SensorModel sensor = SensorModel::autoFromCloud();
  uint64_t dynamic_total = 0;
  for (size_t i = 0; i < std::size(kDynamicScenePersonY); ++i) {
    const PointCloud cloud = dynamicSceneCloud(kDynamicScenePersonY[i]);
    const InsertStats a = cpu.insert(cloud, dynamicScenePose(), sensor);
    const InsertStats b = gpu.insert(cloud, dynamicScenePose(), sensor);
    const std::string what =
        std::string(toString(rule)) + " r" + std::to_string(radius) + " scan " + std::to_string(i);
    EXPECT_EQ(a.rays_dynamic, b.rays_dynamic) << what;
    EXPECT_EQ(a.rays_hit, b.rays_hit) << what;
    expectSameDynamicPoints(cpu, gpu, what);
    expectSameMaps(cpu, gpu, what);
    dynamic_total += b.rays_dynamic;
  }
  // Not a vacuous agreement: the rule found the person's points dynamic on the device too.
  EXPECT_GT(dynamic_total, 0u) << toString(rule) << " r" << radius;
}

TEST(DynamicGpuTest, LabelledRoomSurroundIsByteIdentical) {
  REQUIRE_DEVICE();
  for (int radius : {1, 2}) roomOnBothBackends(VoidSpaceRule::kSurround, radius, true);
}

TEST(DynamicGpuTest, LabelledRoomPassThroughIsByteIdentical) {
  REQUIRE_DEVICE();
  for (int radius : {1, 2}) roomOnBothBackends(VoidSpaceRule::kPassThrough, radius, true);
}

TEST(DynamicGpuTest, LabelledRoomBlockPerSlotApplyIsByteIdentical) {
  REQUIRE_DEVICE();
  roomOnBothBackends(VoidSpaceRule::kSurround, 2, false);
}

/// Every third of W6's first 3 `frames` frames at a quarter of its pixels: the office, people
/// walking, the depth camera's walk (as `fragg_map_sim record` makes them: mount pitch 10
/// degrees).
struct W6Slice {
  std::vector<PointCloud> clouds;
  std::vector<Eigen::Isometry3d> poses;
  size_t dynamic_labels = 0;  ///< points the simulator labelled dynamic
};

W6Slice w6Slice(size_t frames) {
  sim::Scene scene =
      sim::loadScene(std::string(FRAGG_SOURCE_DIR) + "/config/scenes/office_people.json");
  const sim::Terrain terrain = scene.terrain;
  auto ground = [&terrain](double x, double y) { return terrain.heightAt(x, y); };
  const std::vector<sim::PoseSample> samples = sim::sampleTrajectory(
      scene.trajectories.at("walk"), ground, sim::DriftSpec{}, 606, 3 * frames);
  const geometry::MeshBvh bvh(std::move(scene.mesh));
  sim::DepthCameraSpec camera;
  camera.width = 160;
  camera.height = 120;
  camera.hfov_deg = 70;
  camera.max_range_m = 6;
  camera.noise_m = 0.001;
  Eigen::Matrix3d optical;
  optical << 0, 0, 1, -1, 0, 0, 0, -1, 0;  // optical x, y, z in the base frame
  Eigen::Isometry3d T_base_camera = Eigen::Isometry3d::Identity();
  T_base_camera.linear() =
      Eigen::AngleAxisd(10.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()).matrix() * optical;
  W6Slice out;
  std::vector<uint8_t> labels;
  for (size_t i = 0; i < samples.size(); i += 3) {
    const geometry::MeshBvh movers(sim::moversMeshAt(scene.movers, samples[i].stamp_s, ground));
    const Eigen::Isometry3d T = samples[i].T_map_base * T_base_camera;
    out.clouds.push_back(sim::simulateDepthCamera(bvh, camera, T, 606, i, &movers, &labels));
    out.poses.push_back(T);
    for (uint8_t l : labels) out.dynamic_labels += l;
  }
  return out;
}

/// The slice through both backends under the surround rule at 5 cm (W6's resolution), the CUDA
/// map with `pool_slots` slots (0: its default pool).
void w6OnBothBackends(size_t pool_slots) {
  const W6Slice w6 = w6Slice(40);
  ASSERT_GT(w6.dynamic_labels, 0u) << "the slice shows no mover";
  MapParams p = dynamicSceneParams(true, VoidSpaceRule::kSurround, 2);
  p.resolution_m = 0.05;
  Map cpu(p);
  p.backend = Backend::kCuda;
  if (pool_slots > 0) p.cuda.pool_max_bytes = pool_slots * kSlotBytes;
  Map gpu(p);
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, 6.0);
  InsertStats cpu_total, gpu_total;
  for (size_t i = 0; i < w6.clouds.size(); ++i) {
    cpu_total.add(cpu.insert(w6.clouds[i], w6.poses[i], sensor));
    gpu_total.add(gpu.insert(w6.clouds[i], w6.poses[i], sensor));
    const std::string what = "W6 frame " + std::to_string(i);
    EXPECT_EQ(cpu_total.rays_dynamic, gpu_total.rays_dynamic) << what;
    expectSameDynamicPoints(cpu, gpu, what);
    if (i % 8 == 7 || i + 1 == w6.clouds.size()) expectSameMaps(cpu, gpu, what);
  }
  EXPECT_GT(gpu_total.rays_dynamic, 0u) << "no hit classified dynamic";
  if (pool_slots > 0) {
    EXPECT_GT(gpu_total.blocks_evicted, 0u) << "the pool never evicted";
    EXPECT_GT(gpu_total.blocks_uploaded, 0u) << "no block went up again";
  }
}

TEST(DynamicGpuTest, W6SliceIsByteIdentical) {
  REQUIRE_DEVICE();
  w6OnBothBackends(0);
}

TEST(DynamicGpuTest, W6SliceWithSmallPoolIsByteIdentical) {
  REQUIRE_DEVICE();
  w6OnBothBackends(2500);
}

/// W5's LiDAR (config/workloads/w5_movers.args) with 10 % dropout along 12 frames of the drive,
/// NaN points dropped as a KITTI .bin drops them, through both backends with the beam table,
/// clear_no_return_rays and the surround rule.
TEST(DynamicGpuTest, W5SliceUnorganisedNoReturnBeamsIsByteIdentical) {
  REQUIRE_DEVICE();
  sim::Scene scene =
      sim::loadScene(std::string(FRAGG_SOURCE_DIR) + "/config/scenes/campus_movers.json");
  const sim::Terrain terrain = scene.terrain;
  auto ground = [&terrain](double x, double y) { return terrain.heightAt(x, y); };
  const std::vector<sim::PoseSample> samples =
      sim::sampleTrajectory(scene.trajectories.at("drive"), ground, sim::DriftSpec{}, 505, 120);
  const geometry::MeshBvh bvh(std::move(scene.mesh));
  sim::LidarSpec lidar;  // W5's: 32 x 1024, -25..15 degrees
  lidar.max_range_m = 80;
  lidar.range_noise_m = 0.01;
  lidar.dropout = 0.1;
  SensorModel sensor = SensorModel::autoFromCloud(0.0, 30.0);
  sensor.lidar_beams = LidarBeams::evenlySpaced(
      uint32_t(lidar.beams), uint32_t(lidar.azimuth_steps), lidar.elevation_min_deg * M_PI / 180,
      lidar.elevation_max_deg * M_PI / 180);
  MapParams p = dynamicSceneParams(true, VoidSpaceRule::kSurround, 2);
  p.resolution_m = 0.1;
  p.clear_no_return_rays = true;
  Map cpu(p);
  p.backend = Backend::kCuda;
  Map gpu(p);
  uint64_t no_return = 0;
  ASSERT_GE(samples.size(), 100u);
  for (size_t i = 0; i < samples.size(); i += 10) {
    const geometry::MeshBvh movers(sim::moversMeshAt(scene.movers, samples[i].stamp_s, ground));
    const Eigen::Isometry3d T =
        samples[i].T_map_base * Eigen::Translation3d(0, 0, 1.8);  // the record's LiDAR mount
    const PointCloud organised = sim::simulateLidar(bvh, lidar, T, 505, i, &movers);
    PointCloud cloud;
    for (const Eigen::Vector3f& q : organised.points_S)
      if (q.allFinite()) cloud.points_S.push_back(q);
    const InsertStats a = cpu.insert(cloud, T, sensor);
    const InsertStats b = gpu.insert(cloud, T, sensor);
    const std::string what = "W5 frame " + std::to_string(i);
    EXPECT_EQ(a.rays_no_return, b.rays_no_return) << what;
    EXPECT_EQ(a.rays_dynamic, b.rays_dynamic) << what;
    expectSameDynamicPoints(cpu, gpu, what);
    expectSameMaps(cpu, gpu, what);
    no_return += b.rays_no_return;
  }
  EXPECT_GT(no_return, 10u * 1024u) << "few no-return beams: the sky and the dropout give many";
}

}  // namespace
}  // namespace fragg::test
