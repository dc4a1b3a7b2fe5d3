// Frontiers on the CUDA backend against the CPU backend: the same W1-like drive integrated by
// each (with two boxes cleared on the way); after every scan the CUDA map's tracker (updated on
// the device: masks compared per pool slot, neighbourhoods examined there) equals the CPU map's,
// with and without a box and height filter, and full recomputes agree. Needs a
// device (skips without one). Then viewpoint gains: every CUDA gain kernel against the CPU walk.
#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/internal/backend_factory.h"
#include "fragg_map/map.h"
#include "fragg_map/planning/frontier_cells.h"
#include "fragg_map/planning/frontier_clusters.h"
#include "fragg_map/planning/frontier_tracker.h"
#include "fragg_map/planning/viewpoints.h"
#include "fragg_map/sim/lidar_sensor.h"
#include "fragg_map/sim/scene.h"
#include "fragg_map/sim/trajectory.h"
#include "gpu_test_util.h"

namespace fragg::planning {
namespace {

TEST(FrontierGpu, CudaTrackerEqualsCpuOverADrive) {
  REQUIRE_DEVICE();
  sim::Scene scene = sim::loadScene(std::string(FRAGG_SOURCE_DIR) + "/config/scenes/campus.json");
  const sim::Terrain terrain = scene.terrain;
  const auto poses = sim::sampleTrajectory(
      scene.trajectories.at("street"),
      [&terrain](double x, double y) { return terrain.heightAt(x, y); }, sim::DriftSpec(), 7, 60);
  const geometry::MeshBvh bvh(std::move(scene.mesh));
  sim::LidarSpec spec;
  spec.beams = 32;
  spec.azimuth_steps = 720;
  spec.elevation_min_deg = -25;
  spec.elevation_max_deg = 15;
  spec.max_range_m = 60;
  Eigen::Isometry3d T_base_sensor = Eigen::Isometry3d::Identity();
  T_base_sensor.translation().z() = 1.8;

  MapParams p;
  p.resolution_m = 0.1;
  p.backend = Backend::kCpu;
  Map cpu_map(p);
  p.backend = Backend::kCuda;
  Map cuda_map(p);
  FrontierTracker cpu_tracker, cuda_tracker, cuda_host_tracker;
  cuda_tracker.useDevice(true);  // the default
  cuda_host_tracker.useDevice(false);
  FrontierFilter band;
  band.use_height = true;
  band.min_z_m = 0.5;
  band.max_z_m = 2.5;
  FrontierTracker cuda_banded(band);
  cuda_banded.useDevice(true);
  // A box (cell centres tested one by one at its faces) and a band together.
  FrontierFilter boxed = band;
  boxed.use_box = true;
  boxed.box_min_m = Eigen::Vector3d(-20.05, -13.3, -5.0);
  boxed.box_max_m = Eigen::Vector3d(31.7, 18.25, 4.05);
  FrontierTracker cuda_boxed(boxed), cpu_boxed(boxed);
  cuda_boxed.useDevice(true);
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, 30.0);
  uint64_t device_updates = 0, full_updates = 0;
  for (size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Isometry3d T = poses[i].T_map_base * T_base_sensor;
    const PointCloud cloud = sim::simulateLidar(bvh, spec, T, 7, i);
    cpu_map.insert(cloud, T, sensor);
    cuda_map.insert(cloud, T, sensor);
    if (i == 25 || i == 40) {
      // Erased blocks leave the device pool: the device tracker must drop what it saw there
      // and examine their neighbours again.
      const Eigen::Vector3d c = T.translation();
      cpu_map.clearBox(c - Eigen::Vector3d(6.0, 4.0, 3.0), c + Eigen::Vector3d(2.0, 5.0, 1.0));
      cuda_map.clearBox(c - Eigen::Vector3d(6.0, 4.0, 3.0), c + Eigen::Vector3d(2.0, 5.0, 1.0));
    }
    const FrontierUpdateStats cpu_st = cpu_tracker.update(cpu_map);
    const FrontierUpdateStats cuda_st = cuda_tracker.update(cuda_map);
    // The host update fed by the changed-block list compacted on the device.
    const FrontierUpdateStats host_st = cuda_host_tracker.update(cuda_map);
    EXPECT_EQ(host_st.full, i == 0 || i == 25 || i == 40) << "after scan " << i;
    cuda_banded.update(cuda_map);
    cuda_boxed.update(cuda_map);
    cpu_boxed.update(cpu_map);
    EXPECT_FALSE(cpu_st.states_on_device);
    device_updates += cuda_st.states_on_device ? 1 : 0;
    full_updates += cuda_st.full ? 1 : 0;
    ASSERT_EQ(cuda_tracker.size(), cpu_tracker.size()) << "after scan " << i;
    ASSERT_EQ(cuda_host_tracker.size(), cpu_tracker.size()) << "after scan " << i;
    ASSERT_EQ(cuda_boxed.size(), cpu_boxed.size()) << "after scan " << i;
    if (i % 10 == 9 || i < 3 || i == 25 || i == 40) {
      const std::vector<VoxelKey> expected = cpu_tracker.cells();
      ASSERT_EQ(cuda_tracker.cells(), expected) << "after scan " << i;
      ASSERT_EQ(cuda_host_tracker.cells(), expected) << "after scan " << i;
      ASSERT_EQ(findFrontierCells(cuda_map), expected) << "full, after scan " << i;
      ASSERT_EQ(cuda_banded.cells(), findFrontierCells(cpu_map, band)) << "after scan " << i;
      ASSERT_EQ(cuda_boxed.cells(), findFrontierCells(cpu_map, boxed)) << "after scan " << i;
    }
  }
  // Every update ran on the device (the whole map fits its pool); the pool grows during the
  // drive (each growth starts the device state again), so a few updates are full ones.
  EXPECT_EQ(device_updates, poses.size()) << "every update ran on the device";
  EXPECT_LT(full_updates, poses.size() / 2);
  EXPECT_GT(cpu_tracker.size(), 10000u);
  EXPECT_GT(cpu_boxed.size(), 100u);
  EXPECT_LT(cpu_boxed.size(), cpu_tracker.size());

  // A tracker moved from the device to the host and back (the collect/apply pair reads the
  // host): the same set either way.
  {
    FrontierTracker t;
    t.useDevice(true);
    t.update(cuda_map);
    const FrontierMapChanges changes = t.collect(cuda_map);
    EXPECT_TRUE(changes.full) << "a set on the device is not kept on the host";
    t.apply(changes);
    EXPECT_EQ(t.cells(), cpu_tracker.cells());
    const FrontierUpdateStats back = t.update(cuda_map);
    EXPECT_TRUE(back.full && back.states_on_device);
    EXPECT_EQ(t.cells(), cpu_tracker.cells());
  }

  // Viewpoint gains: the CUDA kernel walks the same cells as the CPU walk (the sums may differ
  // by rounding only), for a pinhole camera and a LiDAR.
  std::vector<Eigen::Vector3d> positions;
  std::vector<double> yaws;
  for (size_t i = 0; i < poses.size(); i += 3)
    for (int a = 0; a < 8; ++a) {
      positions.push_back(poses[i].T_map_base.translation() + Eigen::Vector3d(0, 0, 1.2 + 0.1 * a));
      yaws.push_back(0.785 * a - 3.0);
    }
  GainSensor camera;  // 64 x 48 rays, 10 m
  GainSensor lidar;
  lidar.kind = GainSensor::Kind::kLidar;
  lidar.columns = 360;
  lidar.rows = 16;
  lidar.max_range_m = 20.0;
  for (const GainSensor& sensor : {camera, lidar}) {
    const std::vector<double> cpu = viewpointGainsBits(cpu_map, positions, yaws, sensor, 0);
    const std::vector<double> gpu =
        viewpointGainsBits(cuda_map, positions, yaws, sensor, 0, Backend::kCuda);
    ASSERT_EQ(gpu.size(), cpu.size());
    double total = 0.0;
    for (size_t i = 0; i < cpu.size(); ++i) {
      EXPECT_NEAR(gpu[i], cpu[i], 1e-9 * std::max(1.0, cpu[i])) << "viewpoint " << i;
      total += cpu[i];
    }
    EXPECT_GT(total, 1000.0);
  }

  // Every CUDA gain kernel against the CPU walk (GainKernel: boxes of their own size, bitmaps
  // by block from a pool, persistent threads on a ray queue, the entropy summed over the pool
  // after the walk); then the pooled kernels with a pool far too small (the viewpoints that
  // met the full pool are computed again by the sized kernel), every kernel with a bitmap
  // budget that splits the batch into many rounds, and the queued kernels refilling at 1 and
  // at 32 idle lanes. A kernel that throws fails its own case, named; as a CUDA context error
  // is sticky (every later call fails too), the kernels without a pool run first, the
  // clusters' checks on the default kernel next, and the pooled kernels last.
  struct KernelCase {
    GainDeviceOptions device;
    std::string what;
    bool expect_reruns = false, expect_rounds = false;
  };
  std::vector<KernelCase> cases;
  for (const GainKernel k : kGainKernels) {
    KernelCase c;
    c.device.kernel = k;
    c.what = gainKernelName(k);
    cases.push_back(c);
    c.device.bitmap_budget_bytes = size_t(4) << 20;
    c.what += ", 4 MiB of bitmaps a round";
    c.expect_rounds = true;
    cases.push_back(c);
  }
  for (const GainKernel k : {GainKernel::kPooled, GainKernel::kPooledQueued, GainKernel::kDeferred,
                             GainKernel::kPooledDeferred}) {
    KernelCase c;
    c.device.kernel = k;
    c.device.pool_blocks = 64;
    c.what = std::string(gainKernelName(k)) + ", a pool of 64 blocks";
    c.expect_reruns = true;
    cases.push_back(c);
  }
  for (const GainKernel k : {GainKernel::kQueued, GainKernel::kPooledQueued, GainKernel::kDeferred})
    for (const int lanes : {1, 32}) {
      KernelCase c;
      c.device.kernel = k;
      c.device.refill_lanes = lanes;
      c.what = std::string(gainKernelName(k)) + ", refill at " + std::to_string(lanes);
      cases.push_back(c);
    }
  std::stable_partition(cases.begin(), cases.end(),
                        [](const KernelCase& c) { return !gainKernelPooled(c.device.kernel); });
  // The first case that threw (later device errors may be its sticky context error).
  std::string first_throw;
  const auto checkCases = [&](bool pooled_cases) {
    for (const GainSensor& sensor : {camera, lidar}) {
      const std::vector<double> cpu = viewpointGainsBits(cpu_map, positions, yaws, sensor, 0);
      for (const KernelCase& c : cases) {
        if (gainKernelPooled(c.device.kernel) != pooled_cases) continue;
        const std::string what =
            c.what + (sensor.kind == GainSensor::Kind::kLidar ? std::string(", lidar")
                                                              : std::string(", camera"));
        GainTimings t;
        std::vector<double> gpu;
        try {
          gpu = viewpointGainsBits(cuda_map, positions, yaws, sensor, 0, Backend::kCuda, c.device,
                                   &t);
        } catch (const std::exception& e) {
          ADD_FAILURE() << "gain kernel " << what << " threw: " << e.what()
                        << (first_throw.empty()
                                ? std::string()
                                : " (after " + first_throw + " threw: a CUDA error is sticky)");
          if (first_throw.empty()) first_throw = what;
          continue;
        }
        ASSERT_EQ(gpu.size(), cpu.size()) << what;
        for (size_t i = 0; i < cpu.size(); ++i)
          EXPECT_NEAR(gpu[i], cpu[i], 1e-9 * std::max(1.0, cpu[i])) << what << ", viewpoint " << i;
        EXPECT_TRUE(t.on_device) << what;
        const bool pooled = gainKernelPooled(c.device.kernel);
        if (pooled) {
          EXPECT_GT(t.pool_blocks_wanted, 0u) << what;
        }
        if (c.expect_reruns) {
          EXPECT_GT(t.pool_reruns, 0u) << what;
          EXPECT_GT(t.pool_blocks_wanted, c.device.pool_blocks) << what;
        } else if (pooled && !c.expect_rounds) {  // the default pool cannot run out
          EXPECT_EQ(t.pool_reruns, 0u) << what << " (" << t.pool_blocks_wanted << " wanted)";
        }
        if (c.expect_rounds) {
          EXPECT_GT(t.rounds, 1u) << what;
        }
      }
    }
  };
  checkCases(false);

  // Every cluster's viewpoints in one batch (clustersViewpoints): entropy gains on the device
  // for the CUDA map, coverage on the host for both; the same candidates, ranks and gains.
  const std::vector<FrontierCluster> clusters =
      FrontierClusterer().cluster(cpu_map, cpu_tracker.cells());
  ASSERT_GT(clusters.size(), 10u);
  for (const ViewpointGain gain : {ViewpointGain::kEntropy, ViewpointGain::kCoverage}) {
    ViewpointOptions o;
    o.gain = gain;
    o.top_k = 3;
    const auto cpu = clustersViewpoints(cpu_map, clusters, o, 0);
    const auto gpu = clustersViewpoints(cuda_map, clusters, o, 0);
    ASSERT_EQ(gpu.size(), cpu.size());
    size_t views = 0;
    for (size_t c = 0; c < cpu.size(); ++c) {
      ASSERT_EQ(gpu[c].size(), cpu[c].size()) << viewpointGainName(gain) << " cluster " << c;
      for (size_t j = 0; j < cpu[c].size(); ++j) {
        EXPECT_EQ(gpu[c][j].position_m, cpu[c][j].position_m) << "cluster " << c;
        EXPECT_NEAR(gpu[c][j].gain_bits, cpu[c][j].gain_bits,
                    1e-9 * std::max(1.0, cpu[c][j].gain_bits));
      }
      views += cpu[c].size();
    }
    EXPECT_GT(views, 10u) << viewpointGainName(gain);
  }
  checkCases(true);

  // The kernel chosen in the options reaches the batch of every cluster's candidates.
  {
    ViewpointOptions o;
    o.top_k = 3;
    const auto cpu = clustersViewpoints(cpu_map, clusters, o, 0);
    o.device_gains.kernel = GainKernel::kPooledQueued;
    std::vector<std::vector<Viewpoint>> gpu;
    try {
      gpu = clustersViewpoints(cuda_map, clusters, o, 0);
    } catch (const std::exception& e) {
      FAIL() << "clusters' viewpoints by the pooled-queued kernel threw: " << e.what()
             << (first_throw.empty() ? std::string() : " (after " + first_throw + " threw)");
    }
    ASSERT_EQ(gpu.size(), cpu.size());
    for (size_t c = 0; c < cpu.size(); ++c) {
      ASSERT_EQ(gpu[c].size(), cpu[c].size()) << "cluster " << c;
      for (size_t j = 0; j < cpu[c].size(); ++j)
        EXPECT_NEAR(gpu[c][j].gain_bits, cpu[c][j].gain_bits,
                    1e-9 * std::max(1.0, cpu[c][j].gain_bits))
            << "pooled-queued, cluster " << c;
    }
  }
}

}  // namespace
}  // namespace fragg::planning
