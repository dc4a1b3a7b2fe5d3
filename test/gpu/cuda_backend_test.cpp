// The CUDA backend against the CPU backend: same input, byte-identical blocks. Labelled `gpu`;
// every test but the backend-selection one is skipped (with a message) where there is no CUDA
// device, so the suite also runs on the CI machine.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "../core/test_scenes.h"
#include "../test_dir.h"
#include "bench/synthetic_lidar.h"
#include "fragg_map/errors.h"
#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/internal/auto_sensor.h"
#include "fragg_map/internal/backend_factory.h"
#include "fragg_map/io/dataset.h"
#include "fragg_map/io/point_file.h"
#include "fragg_map/io/pose_file.h"
#include "fragg_map/map.h"
#include "fragg_map/sim/lidar_sensor.h"
#include "fragg_map/sim/scene.h"
#include "fragg_map/sim/trajectory.h"
#include "gpu_test_util.h"

namespace fragg {
namespace {

const std::string kData = FRAGG_REAL_DATA;

std::string deviceName() {
  std::string why;
  return cudaDeviceName(0, &why);
}

MapParams paramsFor(Backend b, double res) {
  MapParams p;
  p.resolution_m = res;
  p.backend = b;
  return p;
}

/// Every block of `a` is in `b` with the same 2 KiB, and the other way round; with
/// `same_history` (two live maps given the same operations) also the same revisions.
void expectSameBlocks(const Map& a, const Map& b, const char* what, bool same_history = true) {
  const BlockView ba = a.blockView();
  const BlockView bb = b.blockView();
  size_t differing = 0, missing = 0, observed_cells = 0, meta_differing = 0;
  ba.forEach([&](const BlockKey& key, const Block& block) {
    const Block* other = bb.findBlock(key);
    if (!other) {
      ++missing;
      return;
    }
    if (std::memcmp(&block, other, sizeof(Block)) != 0) ++differing;
    // The revisions incremental publishing reads (markers) must agree as well.
    const BlockStamps sa = ba.stamps(key), sb = bb.stamps(key);
    if (same_history && (sa.changed_at != sb.changed_at || sa.occupied_at != sb.occupied_at))
      ++meta_differing;
    for (const Cell& c : block.cells) observed_cells += c.observed();
  });
  EXPECT_EQ(ba.size(), bb.size()) << what;
  EXPECT_EQ(missing, 0u) << what;
  EXPECT_EQ(differing, 0u) << what << ": blocks whose bytes differ";
  EXPECT_EQ(meta_differing, 0u) << what << ": blocks whose changed_at / occupied_at differ";
  EXPECT_GT(observed_cells, 1000u) << what;
  std::printf("[gpu] %s: %zu blocks, %zu observed cells, %zu differing\n", what, ba.size(),
              observed_cells, differing);
}

struct Input {
  PointCloud cloud;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
};

void insertAll(Map& m, const std::vector<Input>& in, const SensorModel& sensor) {
  for (const Input& s : in) m.insert(s.cloud, s.T, sensor);
}

std::vector<Input> velodynePair() {
  const std::string dir = kData + "/small_gicp_pair/";
  return {{readPointFile(dir + "target.ply"), Eigen::Isometry3d::Identity()},
          {readPointFile(dir + "source.ply"), readMatrix4(dir + "T_target_source.txt")}};
}

std::vector<Input> rgbdFrames() {
  auto source = openDataset(kData + "/slambook2_ch5_rgbd");
  std::vector<Input> out;
  Scan s;
  while (source->next(s)) out.push_back({s.cloud, s.T_map_sensor});
  return out;
}

std::vector<Input> syntheticLidar(int scans, double step_m) {
  bench::SyntheticLidarOptions o;
  o.step_m = step_m;
  bench::SyntheticLidar lidar(o);
  std::vector<Input> out;
  for (int i = 0; i < scans; ++i) {
    Scan s = lidar.scan(i);
    out.push_back({s.cloud, s.T_map_sensor});
  }
  return out;
}

/// The drive, then the same scans in reverse order (back to the start).
std::vector<Input> outAndBack(std::vector<Input> scans) {
  std::vector<Input> back(scans.rbegin(), scans.rend());
  scans.insert(scans.end(), back.begin(), back.end());
  return scans;
}

/// W1 itself (config/workloads/w1_lidar360.args): the campus street, 128 x 1406 LiDAR at
/// 1.8 m, -25..15 deg, 2 cm noise, seed 101; every `step`-th of the first 100 frames.
std::vector<Input> simulatedW1(int step) {
  sim::Scene scene = sim::loadScene(std::string(FRAGG_SOURCE_DIR) + "/config/scenes/campus.json");
  const sim::Terrain terrain = scene.terrain;
  const auto poses = sim::sampleTrajectory(
      scene.trajectories.at("street"),
      [&terrain](double x, double y) { return terrain.heightAt(x, y); }, sim::DriftSpec(), 101,
      100);
  const geometry::MeshBvh bvh(std::move(scene.mesh));
  sim::LidarSpec spec;
  spec.beams = 128;
  spec.azimuth_steps = 1406;
  spec.elevation_min_deg = -25;
  spec.elevation_max_deg = 15;
  spec.max_range_m = 80;
  spec.range_noise_m = 0.02;
  Eigen::Isometry3d T_base_sensor = Eigen::Isometry3d::Identity();
  T_base_sensor.translation().z() = 1.8;
  std::vector<Input> out;
  for (size_t i = 0; i < poses.size(); i += step) {
    const Eigen::Isometry3d T = poses[i].T_map_base * T_base_sensor;
    out.push_back({sim::simulateLidar(bvh, spec, T, 101, i), T});
  }
  return out;
}

void expectBackendsAgree(const std::vector<Input>& in, MapParams p, const SensorModel& sensor,
                         const char* what) {
  p.backend = Backend::kCpu;
  Map cpu(p);
  p.backend = Backend::kCuda;
  Map gpu(p);
  ASSERT_STREQ(gpu.backendName(), "cuda");
  insertAll(cpu, in, sensor);
  insertAll(gpu, in, sensor);
  expectSameBlocks(cpu, gpu, what);
}

/// The CUDA map inserts `order` (indices into `in`, an index may repeat: the same cloud object
/// again) with one Map::insertSequence call, sensors taken in turn; the CPU map one insert()
/// at a time. Returns the CUDA map's scans whose points were staged during the scan before.
uint64_t expectSequenceAgrees(const std::vector<Input>& in, const std::vector<size_t>& order,
                              MapParams p, const std::vector<SensorModel>& sensors,
                              const char* what) {
  p.backend = Backend::kCpu;
  Map cpu(p);
  p.backend = Backend::kCuda;
  Map gpu(p);
  std::vector<ScanToInsert> batch;
  for (size_t k = 0; k < order.size(); ++k) {
    ScanToInsert s;
    s.cloud = &in[order[k]].cloud;
    s.T_map_sensor = in[order[k]].T;
    s.sensor = sensors[k % sensors.size()];
    cpu.insert(*s.cloud, s.T_map_sensor, s.sensor);
    batch.push_back(s);
  }
  InsertStats total;
  for (const InsertStats& st : gpu.insertSequence(batch)) total.add(st);
  EXPECT_STREQ(gpu.backendName(), "cuda") << gpu.backendReason();
  std::printf("[gpu] %s: %llu of %zu scans staged during the scan before\n", what,
              static_cast<unsigned long long>(total.scans_staged), order.size());
  expectSameBlocks(cpu, gpu, what);
  return total.scans_staged;
}

std::vector<size_t> firstN(size_t n) {
  std::vector<size_t> out(n);
  for (size_t i = 0; i < n; ++i) out[i] = i;
  return out;
}

TEST(CudaBackendTest, AutoPicksCudaWithADeviceAndTheCpuOtherwise) {
  Map m(paramsFor(Backend::kAuto, 0.05));
  if (builtWithCuda() && !deviceName().empty()) {
    EXPECT_STREQ(m.backendName(), "cuda");
    EXPECT_NE(m.backendReason().find(deviceName()), std::string::npos) << m.backendReason();
  } else {
    EXPECT_STREQ(m.backendName(), "cpu");
    EXPECT_EQ(m.backendReason().rfind("auto: CPU backend (", 0), 0u) << m.backendReason();
    EXPECT_THROW(Map(paramsFor(Backend::kCuda, 0.05)), InvalidArgument);
  }
  EXPECT_STREQ(Map(paramsFor(Backend::kCpu, 0.05)).backendName(), "cpu");
}

TEST(CudaBackendTest, RealVelodynePairIsByteIdentical) {
  REQUIRE_DEVICE();
  expectBackendsAgree(velodynePair(), paramsFor(Backend::kCuda, 0.05),
                      SensorModel::autoFromCloud(0.0, 30.0), "velodyne pair 5 cm 30 m");
}

TEST(CudaBackendTest, RealRgbdFramesAreByteIdentical) {
  REQUIRE_DEVICE();
  expectBackendsAgree(rgbdFrames(), paramsFor(Backend::kCuda, 0.03),
                      SensorModel::autoFromCloud(0.0, -1.0), "rgbd 3 cm");
}

TEST(CudaBackendTest, RealRoomScansAreByteIdentical) {
  REQUIRE_DEVICE();
  const std::string dir = kData + "/pcl_room_scans/";
  expectBackendsAgree(
      {{readPointFile(dir + "room_scan1.pcd")}, {readPointFile(dir + "room_scan2.pcd")}},
      paramsFor(Backend::kCuda, 0.05), SensorModel::autoFromCloud(0.0, -1.0), "room scans 5 cm");
}

TEST(CudaBackendTest, SyntheticLidar180kIsByteIdenticalAt30And50Metres) {
  REQUIRE_DEVICE();
  const auto scans = syntheticLidar(6, 2.0);
  expectBackendsAgree(scans, paramsFor(Backend::kCuda, 0.05), SensorModel::autoFromCloud(0.0, 30.0),
                      "synthetic 180k 30 m");
  expectBackendsAgree(scans, paramsFor(Backend::kCuda, 0.05), SensorModel::autoFromCloud(0.0, 50.0),
                      "synthetic 180k 50 m");
}

TEST(CudaBackendTest, SimulatedW1IsByteIdenticalAt30And50Metres) {
  REQUIRE_DEVICE();
  const auto scans = simulatedW1(5);
  ASSERT_EQ(scans.size(), 20u);
  expectBackendsAgree(scans, paramsFor(Backend::kCuda, 0.05), SensorModel::autoFromCloud(0.0, 30.0),
                      "W1 (20 of 100 scans) 30 m");
  expectBackendsAgree(scans, paramsFor(Backend::kCuda, 0.05), SensorModel::autoFromCloud(0.0, 50.0),
                      "W1 (20 of 100 scans) 50 m");
}

TEST(CudaBackendTest, OptionsMatchTheCpu) {
  REQUIRE_DEVICE();
  const auto scans = syntheticLidar(3, 3.0);
  MapParams p = paramsFor(Backend::kCuda, 0.1);
  p.raycast = RayCast::kBresenham;
  expectBackendsAgree(scans, p, SensorModel::autoFromCloud(0.0, 30.0), "bresenham");
  p = paramsFor(Backend::kCuda, 0.1);
  p.cuda.readonly_ray_loads = false;
  p.cuda.pinned_host_blocks = false;
  expectBackendsAgree(scans, p, SensorModel::autoFromCloud(0.0, 30.0), "plain loads, pageable");
  p = paramsFor(Backend::kCuda, 0.1);
  p.clear_no_return_rays = true;
  expectBackendsAgree(scans, p, SensorModel::autoFromCloud(0.0, 30.0), "no-return clearing");
  p = paramsFor(Backend::kCuda, 0.1);
  p.cuda.warp_per_slot_apply = false;
  p.cuda.device_auto_sensor = false;
  expectBackendsAgree(scans, p, SensorModel::autoFromCloud(0.0, 30.0),
                      "a thread block per slot in apply, auto model on the host");
  p = paramsFor(Backend::kCuda, 0.1);
  expectBackendsAgree(scans, p,
                      SensorModel::spinningLidar(-20 * M_PI / 180, 10 * M_PI / 180, 1.0, 25.0),
                      "explicit lidar model, min range");
  // octomap_server's cut cell rule: rays cut at 8 m (the scans reach 30 m) free their cut cell,
  // through the piece walk and the one-thread-a-ray walk, DDA and Bresenham.
  for (int pieces : {192, 0})
    for (RayCast raycast : {RayCast::kDda, RayCast::kBresenham}) {
      p = paramsFor(Backend::kCuda, 0.1);
      p.free_cut_cell = true;
      p.cuda.ray_piece_steps = pieces;
      p.raycast = raycast;
      expectBackendsAgree(
          scans, p, SensorModel::autoFromCloud(0.0, 8.0),
          raycast == RayCast::kDda ? "free cut cell, dda" : "free cut cell, bresenham");
    }
}

/// RayCast::kOctomap (computeRayKeys's arithmetic, one thread a ray whatever ray_piece_steps
/// says): the same bytes as the CPU on W1 at 5 cm, with the cut cell rule, with no-return
/// clearing (rays prepared on the host) and with skipping saturated blocks off.
TEST(CudaBackendTest, OctomapRaycastIsByteIdentical) {
  REQUIRE_DEVICE();
  const auto w1 = simulatedW1(5);
  MapParams p = paramsFor(Backend::kCuda, 0.05);
  p.raycast = RayCast::kOctomap;
  expectBackendsAgree(w1, p, SensorModel::autoFromCloud(0.0, 30.0), "octomap raycast, W1 30 m");
  const auto scans = syntheticLidar(3, 3.0);
  p = paramsFor(Backend::kCuda, 0.1);
  p.raycast = RayCast::kOctomap;
  p.free_cut_cell = true;
  p.cuda.ray_piece_steps = 0;
  expectBackendsAgree(scans, p, SensorModel::autoFromCloud(0.0, 8.0), "octomap raycast, cut cell");
  p = paramsFor(Backend::kCuda, 0.1);
  p.raycast = RayCast::kOctomap;
  p.clear_no_return_rays = true;
  p.skip_saturated_blocks = false;
  expectBackendsAgree(scans, p, SensorModel::autoFromCloud(0.0, 30.0),
                      "octomap raycast, no-return clearing, no saturated skip");
}

TEST(CudaBackendTest, InsertSequenceStagesTheNextCloudAndIsByteIdentical) {
  REQUIRE_DEVICE();
  const SensorModel auto30 = SensorModel::autoFromCloud(0.0, 30.0);
  const auto w1 = simulatedW1(5);
  EXPECT_EQ(expectSequenceAgrees(w1, firstN(w1.size()), paramsFor(Backend::kCuda, 0.05), {auto30},
                                 "W1 (20 scans) 30 m, one sequence"),
            w1.size() - 1);
  // Auto and explicit models in turn (statistics staged or not), the same cloud object twice
  // in a row, the auto model on the host.
  const auto synth = syntheticLidar(4, 2.0);
  const std::vector<size_t> repeats = {0, 1, 1, 2, 3, 3, 2};
  const SensorModel lidar =
      SensorModel::spinningLidar(-20 * M_PI / 180, 10 * M_PI / 180, 1.0, 25.0);
  EXPECT_EQ(expectSequenceAgrees(synth, repeats, paramsFor(Backend::kCuda, 0.1), {auto30, lidar},
                                 "models in turn, a cloud twice"),
            repeats.size() - 1);
  MapParams host_auto = paramsFor(Backend::kCuda, 0.1);
  host_auto.cuda.device_auto_sensor = false;
  expectSequenceAgrees(synth, repeats, host_auto, {auto30}, "auto model on the host");
  // A tiny pool: evictions, and passes redone behind a staged upload.
  MapParams small = paramsFor(Backend::kCuda, 0.1);
  small.cuda.pool_max_bytes = size_t(12000) * test::kSlotBytes;
  const auto drive = outAndBack(syntheticLidar(8, 4.0));
  expectSequenceAgrees(drive, firstN(drive.size()), small, {SensorModel::autoFromCloud(0.0, 20.0)},
                       "tiny pool out and back");
  // Organised frames with no-return clearing are prepared on the host: nothing is staged.
  MapParams no_return = paramsFor(Backend::kCuda, 0.03);
  no_return.clear_no_return_rays = true;
  const auto frames = rgbdFrames();
  EXPECT_EQ(expectSequenceAgrees(frames, firstN(frames.size()), no_return,
                                 {SensorModel::autoFromCloud()}, "rgbd, no-return clearing"),
            0u);
  expectSequenceAgrees(frames, firstN(frames.size()), paramsFor(Backend::kCuda, 0.03),
                       {SensorModel::autoFromCloud()}, "rgbd");
}

TEST(CudaBackendTest, PrepareKernelCountsLikeTheCpu) {
  REQUIRE_DEVICE();
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-40.f, 40.f);
  PointCloud cloud;
  for (int i = 0; i < 50000; ++i) cloud.points_S.emplace_back(u(rng), u(rng), u(rng) * 0.3f);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  for (int i = 0; i < 100; ++i) {
    cloud.points_S.emplace_back(nan, 1.f, 1.f);
    cloud.points_S.emplace_back(1.f, inf, 1.f);
    cloud.points_S.emplace_back(0.f, 0.f, 0.f);
    cloud.points_S.emplace_back(0.1f, 0.1f, 0.f);  // closer than min range
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translate(Eigen::Vector3d(1.234, -5.678, 0.9));
  T.rotate(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, 0.3, 1).normalized()));
  const SensorModel sensor = SensorModel::pinhole(1.2, 0.8, 0.5, 30.0);
  Map cpu(paramsFor(Backend::kCpu, 0.1)), gpu(paramsFor(Backend::kCuda, 0.1));
  const InsertStats a = cpu.insert(cloud, T, sensor), b = gpu.insert(cloud, T, sensor);
  EXPECT_EQ(a.points_in, b.points_in);
  EXPECT_EQ(a.rays_hit, b.rays_hit);
  EXPECT_EQ(a.rays_free_only, b.rays_free_only);
  EXPECT_EQ(a.dropped_invalid, b.dropped_invalid);
  EXPECT_EQ(a.dropped_min_range, b.dropped_min_range);
  EXPECT_EQ(a.dropped_outside_frustum, b.dropped_outside_frustum);
  EXPECT_GT(a.dropped_outside_frustum, 1000u);
  EXPECT_EQ(a.voxel_visits, b.voxel_visits);
  EXPECT_EQ(a.cells_updated, b.cells_updated);
  EXPECT_EQ(a.blocks_touched, b.blocks_touched);
  EXPECT_EQ(a.blocks_created, b.blocks_created);
  expectSameBlocks(cpu, gpu, "random cloud, pinhole");
}

uint64_t doubleBits(double v) {
  uint64_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

void expectSameStats(const AutoSensorStats& a, const AutoSensorStats& b, const char* what) {
  EXPECT_EQ(doubleBits(a.max_dist_m), doubleBits(b.max_dist_m)) << what;
  EXPECT_EQ(doubleBits(a.sin_min), doubleBits(b.sin_min)) << what;
  EXPECT_EQ(doubleBits(a.sin_max), doubleBits(b.sin_max)) << what;
  for (int i = 0; i < 3; ++i) EXPECT_EQ(a.dir_sum_fx[i], b.dir_sum_fx[i]) << what << " " << i;
  EXPECT_EQ(a.valid, b.valid) << what;
  for (int k = 0; k < 6; ++k) {
    EXPECT_EQ(a.fit[k].fits, b.fit[k].fits) << what << " axis " << k;
    EXPECT_EQ(doubleBits(a.fit[k].tan_h), doubleBits(b.fit[k].tan_h)) << what << " axis " << k;
    EXPECT_EQ(doubleBits(a.fit[k].tan_v), doubleBits(b.fit[k].tan_v)) << what << " axis " << k;
  }
}

/// The auto sensor model's statistics gathered on the device (CudaBackend::autoSensorStats,
/// beside the points' upload) have the bits of the host's gatherAutoSensorStats(), and a map
/// inserting through it reports the host's model.
TEST(CudaBackendTest, AutoSensorStatsOnTheDeviceHaveTheHostsBits) {
  REQUIRE_DEVICE();
  BackendChoice choice = makeBackend(paramsFor(Backend::kCuda, 0.05));
  ASSERT_STREQ(choice.backend->name(), "cuda");
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  PointCloud mixed;  // a camera's points, a LiDAR's, invalid ones, z = -0
  for (int i = 0; i < 30011; ++i) {
    const float z = 0.5f + 4.f * std::fabs(u(rng));
    if (i % 3 == 0)
      mixed.points_S.emplace_back(u(rng) * 0.6f * z, u(rng) * 0.45f * z, z);
    else if (i % 3 == 1)
      mixed.points_S.emplace_back(u(rng) * 20.f, u(rng) * 20.f, u(rng) * 2.f);
    else
      mixed.points_S.emplace_back(u(rng) * 20.f, u(rng) * 20.f, -0.f);
  }
  mixed.points_S.emplace_back(std::numeric_limits<float>::quiet_NaN(), 1.f, 1.f);
  mixed.points_S.emplace_back(1.f, -std::numeric_limits<float>::infinity(), 1.f);
  mixed.points_S.emplace_back(0.f, 0.f, 0.f);
  const std::vector<std::pair<const char*, PointCloud>> clouds = {
      {"velodyne", velodynePair()[0].cloud},
      {"rgbd frame", rgbdFrames()[0].cloud},
      {"W1 scan", simulatedW1(50)[0].cloud},
      {"mixed", mixed},
      {"empty", PointCloud()}};
  for (const auto& [what, cloud] : clouds) {
    AutoSensorStats device;
    ASSERT_TRUE(choice.backend->autoSensorStats(cloud, &device, false)) << what;
    const AutoSensorStats host = gatherAutoSensorStats(cloud);
    expectSameStats(device, host, what);
    EXPECT_EQ(device.valid > 0, !cloud.empty()) << what;
  }
  // Through a map: the model each insertion reports, on the device and on the host.
  MapParams p = paramsFor(Backend::kCuda, 0.03);
  Map gpu(p);
  p.cuda.device_auto_sensor = false;
  Map host(p);
  for (const Input& in : rgbdFrames()) {
    const InsertStats a = gpu.insert(in.cloud, in.T, SensorModel::autoFromCloud());
    const InsertStats b = host.insert(in.cloud, in.T, SensorModel::autoFromCloud());
    ASSERT_EQ(a.sensor.type, SensorType::kPinhole);
    EXPECT_EQ(a.sensor.describe(), b.sensor.describe());
    EXPECT_EQ(a.sensor.hfov_rad, b.sensor.hfov_rad);
    EXPECT_EQ(a.sensor.vfov_rad, b.sensor.vfov_rad);
    EXPECT_EQ(a.sensor.forward_S, b.sensor.forward_S);
    EXPECT_EQ(a.sensor.max_range_m, b.sensor.max_range_m);
  }
  expectSameBlocks(host, gpu, "rgbd 3 cm, auto model on the device and on the host");
}

/// Free-only points (filter_ground's ground points): the device's prepare kernel reads the
/// flags and gives the same rays, counters and cells as the CPU, on the device path (an
/// unorganised cloud) and on the host path (an organised one with no-return rays).
TEST(CudaBackendTest, FreeOnlyPointsAreByteIdentical) {
  REQUIRE_DEVICE();
  std::vector<Input> in = velodynePair();
  for (Input& s : in) {
    s.cloud.free_only.resize(s.cloud.size());
    for (size_t i = 0; i < s.cloud.size(); ++i)
      s.cloud.free_only[i] = s.cloud.points_S[i].z() < -1.0f || i % 7 == 0 ? 1 : 0;
  }
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, 30.0);
  Map cpu(paramsFor(Backend::kCpu, 0.05)), gpu(paramsFor(Backend::kCuda, 0.05));
  ASSERT_STREQ(gpu.backendName(), "cuda");
  for (const Input& s : in) {
    const InsertStats a = cpu.insert(s.cloud, s.T, sensor), b = gpu.insert(s.cloud, s.T, sensor);
    EXPECT_EQ(a.rays_hit, b.rays_hit);
    EXPECT_EQ(a.rays_free_only, b.rays_free_only);
    EXPECT_GT(a.rays_free_only, 1000u);
    EXPECT_EQ(a.cells_updated, b.cells_updated);
  }
  expectSameBlocks(cpu, gpu, "velodyne pair, free-only points");

  MapParams p = paramsFor(Backend::kCpu, 0.05);
  p.clear_no_return_rays = true;
  std::vector<Input> room = {
      {test::roomScan(3.0, 1.0, 1.5, 32, 360), Eigen::Isometry3d::Identity()}};
  PointCloud& c = room[0].cloud;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  c.free_only.resize(c.size());
  for (size_t i = 0; i < c.size(); ++i) {
    if (i % 11 == 0) c.points_S[i] = Eigen::Vector3f::Constant(nan);
    c.free_only[i] = c.points_S[i].z() < -0.98f ? 1 : 0;
  }
  expectBackendsAgree(room, p, SensorModel::autoFromCloud(0.0, 10.0),
                      "organised room, no-return rays and free-only points");
}

TEST(CudaBackendTest, TinyPoolEvictsWritesBackAndReuploads) {
  REQUIRE_DEVICE();
  // A pool of ~12,000 slots against a drive that touches far more: blocks go back and forth.
  // The path goes out and back, so evicted blocks are uploaded again.
  const auto scans = outAndBack(syntheticLidar(8, 4.0));
  MapParams p = paramsFor(Backend::kCuda, 0.1);
  p.cuda.pool_max_bytes = size_t(12000) * test::kSlotBytes;
  Map gpu(p);
  p.backend = Backend::kCpu;
  Map cpu(p);
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, 20.0);
  InsertStats total;
  for (size_t i = 0; i < scans.size(); ++i) {
    cpu.insert(scans[i].cloud, scans[i].T, sensor);
    total.add(gpu.insert(scans[i].cloud, scans[i].T, sensor));
    if (i == 5) {  // a host reader in the middle: write-back, then the device goes on
      const Eigen::Vector3d p_map = scans[0].T.translation() + Eigen::Vector3d(3, 0, -1.7);
      EXPECT_EQ(cpu.query(p_map), gpu.query(p_map));
    }
  }
  ASSERT_STREQ(gpu.backendName(), "cuda") << gpu.backendReason();
  EXPECT_GT(total.blocks_evicted, 1000u);
  EXPECT_GT(total.blocks_uploaded, 1000u);
  std::printf("[gpu] tiny pool: %llu evicted, %llu uploaded, device %zu MiB\n",
              static_cast<unsigned long long>(total.blocks_evicted),
              static_cast<unsigned long long>(total.blocks_uploaded),
              gpu.memory().device_bytes >> 20);
  expectSameBlocks(cpu, gpu, "tiny pool, out and back");
}

/// CUDA with the saturated-block skip (the default) against the CPU without it: the same bytes,
/// fewer visits on the device.
void expectSkipIsExact(const std::vector<Input>& scans, MapParams p, const SensorModel& sensor,
                       const char* what) {
  p.backend = Backend::kCuda;
  Map gpu(p);
  p.backend = Backend::kCpu;
  p.skip_saturated_blocks = false;
  Map cpu(p);
  uint64_t visits_gpu = 0, visits_cpu = 0;
  for (const Input& s : scans) {
    visits_gpu += gpu.insert(s.cloud, s.T, sensor).voxel_visits;
    visits_cpu += cpu.insert(s.cloud, s.T, sensor).voxel_visits;
  }
  ASSERT_STREQ(gpu.backendName(), "cuda") << gpu.backendReason();
  std::printf("[gpu] %s: %llu visits with the skip (cuda), %llu without (cpu): %.1f %%\n", what,
              static_cast<unsigned long long>(visits_gpu),
              static_cast<unsigned long long>(visits_cpu), 100.0 * visits_gpu / visits_cpu);
  EXPECT_LT(visits_gpu, visits_cpu) << what;
  expectSameBlocks(cpu, gpu, what);
}

TEST(CudaBackendTest, SaturatedBlockSkipIsExact) {
  REQUIRE_DEVICE();
  expectSkipIsExact(simulatedW1(4), paramsFor(Backend::kCuda, 0.05),
                    SensorModel::autoFromCloud(0.0, 30.0), "W1 (25 of 100 scans) 30 m, skip");
  // Evictions and uploads: a slot that leaves must not carry its flag to the next block.
  MapParams small = paramsFor(Backend::kCuda, 0.1);
  small.cuda.pool_max_bytes = size_t(12000) * test::kSlotBytes;
  expectSkipIsExact(outAndBack(syntheticLidar(8, 4.0)), small,
                    SensorModel::autoFromCloud(0.0, 20.0), "tiny pool out and back, skip");
}

TEST(CudaBackendTest, HostReadersSeeDeviceChanges) {
  REQUIRE_DEVICE();
  const auto scans = syntheticLidar(4, 2.0);
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, 30.0);
  Map cpu(paramsFor(Backend::kCpu, 0.1)), gpu(paramsFor(Backend::kCuda, 0.1));
  insertAll(cpu, {scans[0], scans[1]}, sensor);
  insertAll(gpu, {scans[0], scans[1]}, sensor);
  // save (write-back), clear a box on the host (device copies dropped), insert more.
  const std::string path = fragg::test::testDir() + "/gpu_save.fgm";
  gpu.save(path);
  expectSameBlocks(cpu, Map::load(path), "saved after 2 scans", /*same_history=*/false);
  const Eigen::Vector3d lo = scans[1].T.translation() - Eigen::Vector3d(4, 4, 2);
  const Eigen::Vector3d hi = scans[1].T.translation() + Eigen::Vector3d(4, 4, 2);
  cpu.clearBox(lo, hi);
  gpu.clearBox(lo, hi);
  insertAll(cpu, {scans[2], scans[3]}, sensor);
  insertAll(gpu, {scans[2], scans[3]}, sensor);
  EXPECT_EQ(cpu.knownVoxelCount(), gpu.knownVoxelCount());
  expectSameBlocks(cpu, gpu, "clear box, then 2 more scans");
  gpu.reset();
  cpu.reset();
  insertAll(cpu, {scans[3]}, sensor);
  insertAll(gpu, {scans[3]}, sensor);
  expectSameBlocks(cpu, gpu, "after reset");
}

TEST(CudaBackendTest, PoolTooSmallForOneScanFallsBackToTheCpu) {
  REQUIRE_DEVICE();
  const auto scans = syntheticLidar(3, 2.0);
  MapParams p = paramsFor(Backend::kCuda, 0.05);
  p.cuda.pool_max_bytes = size_t(200) * test::kSlotBytes;  // far fewer slots than one scan touches
  Map gpu(p);
  p.backend = Backend::kCpu;
  Map cpu(p);
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, 30.0);
  insertAll(cpu, scans, sensor);
  insertAll(gpu, scans, sensor);
  EXPECT_STREQ(gpu.backendName(), "cpu");
  EXPECT_NE(gpu.backendReason().find("fell back from CUDA"), std::string::npos);
  expectSameBlocks(cpu, gpu, "after the fallback");
}

/// A small pose error of scan i, growing along the drive (as odometry drift does).
Eigen::Isometry3d driftOf(size_t i) {
  Eigen::Isometry3d d = Eigen::Isometry3d::Identity();
  d.translation() = Eigen::Vector3d(0.02 * i, -0.01 * i, 0.0);
  d.linear() = Eigen::AngleAxisd(0.002 * i, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return d;
}

/// Both backends build from drifted poses with the scan store on, then correct `fix` scans
/// back to their true poses and remove one; the blocks must stay byte-identical throughout.
CorrectionStats expectCorrectionAgrees(const std::vector<Input>& in, MapParams p,
                                       const SensorModel& sensor, const std::vector<size_t>& fix,
                                       const char* what) {
  p.scans.keep = true;
  p.backend = Backend::kCpu;
  Map cpu(p);
  p.backend = Backend::kCuda;
  Map gpu(p);
  for (size_t i = 0; i < in.size(); ++i) {
    cpu.insert(in[i].cloud, in[i].T * driftOf(i), sensor);
    gpu.insert(in[i].cloud, in[i].T * driftOf(i), sensor);
  }
  std::map<ScanId, Eigen::Isometry3d> poses;
  for (size_t i : fix) poses[ScanId(i)] = in[i].T;
  const CorrectionStats a = cpu.correctPoses(poses);
  const CorrectionStats b = gpu.correctPoses(poses);
  EXPECT_STREQ(gpu.backendName(), "cuda") << gpu.backendReason();
  EXPECT_EQ(a.removal.cells_updated, b.removal.cells_updated) << what;
  EXPECT_EQ(a.insertion.cells_updated, b.insertion.cells_updated) << what;
  // Each removal and re-insertion after the first had its points staged during the one before.
  EXPECT_EQ(b.removal.scans_staged + b.insertion.scans_staged, 2 * fix.size() - 1) << what;
  std::printf(
      "[gpu] %s: %zu scans corrected, CPU %.1f ms, CUDA %.1f ms (uploaded %llu)\n", what,
      fix.size(), a.seconds_total * 1e3, b.seconds_total * 1e3,
      static_cast<unsigned long long>(b.removal.blocks_uploaded + b.insertion.blocks_uploaded));
  expectSameBlocks(cpu, gpu, (std::string(what) + ", corrected").c_str());
  cpu.remove(0);
  gpu.remove(0);
  expectSameBlocks(cpu, gpu, (std::string(what) + ", scan 0 removed").c_str());
  return b;
}

TEST(CudaBackendTest, PoseCorrectionIsByteIdenticalOnRealScans) {
  REQUIRE_DEVICE();
  expectCorrectionAgrees(velodynePair(), paramsFor(Backend::kCuda, 0.05),
                         SensorModel::autoFromCloud(0.0, 30.0), {1}, "velodyne pair");
  expectCorrectionAgrees(rgbdFrames(), paramsFor(Backend::kCuda, 0.03),
                         SensorModel::autoFromCloud(), {2, 3, 4}, "rgbd frames");
}

TEST(CudaBackendTest, PoseCorrectionOfEvictedScansIsByteIdentical) {
  REQUIRE_DEVICE();
  // A small pool and a drive out and back: the blocks around the far end have left the device
  // by the time the scans taken there are corrected, so removal uploads them (and evicts
  // others) first. 16,000 slots: fewer than the drive's ~20,000 blocks, more than one scan's.
  const auto scans = outAndBack(syntheticLidar(8, 4.0));
  MapParams p = paramsFor(Backend::kCuda, 0.1);
  p.cuda.pool_max_bytes = size_t(16000) * test::kSlotBytes;
  const CorrectionStats st = expectCorrectionAgrees(scans, p, SensorModel::autoFromCloud(0.0, 20.0),
                                                    {6, 7, 8, 9}, "small pool, out and back");
  EXPECT_GT(st.removal.blocks_uploaded + st.insertion.blocks_uploaded, 0u);
}

TEST(CudaBackendTest, RaysCutIntoPiecesAreByteIdentical) {
  REQUIRE_DEVICE();
  // Pieces of 1 cell: rays longer than 64 cells along their major axis get longer pieces (the
  // cap); 4096: one piece a ray through the pieces kernel; 0: one thread a ray. With the skip
  // (pieces that start inside a saturated block) against the CPU without it.
  const auto w1 = simulatedW1(10);
  for (int steps : {0, 1, 5, 32, 4096}) {
    MapParams p = paramsFor(Backend::kCuda, 0.05);
    p.cuda.ray_piece_steps = steps;
    const std::string what = "W1 (10 scans) 50 m, pieces of " + std::to_string(steps);
    expectSkipIsExact(w1, p, SensorModel::autoFromCloud(0.0, 50.0), what.c_str());
  }
  // Evictions and passes redone; removal and correction walk pieces too; noise margins.
  MapParams small = paramsFor(Backend::kCuda, 0.1);
  small.cuda.pool_max_bytes = size_t(16000) * test::kSlotBytes;
  small.cuda.ray_piece_steps = 3;
  expectCorrectionAgrees(outAndBack(syntheticLidar(8, 4.0)), small,
                         SensorModel::autoFromCloud(0.0, 20.0), {6, 7, 8, 9},
                         "small pool, out and back, pieces of 3");
  SensorModel noisy = SensorModel::autoFromCloud(0.0, 30.0);
  noisy.range_noise_m = 0.02;
  MapParams p = paramsFor(Backend::kCuda, 0.05);
  p.cuda.ray_piece_steps = 7;
  expectCorrectionAgrees(velodynePair(), p, noisy, {1}, "velodyne pair, 2 cm noise, pieces of 7");
}

TEST(CudaBackendTest, RangeNoiseMarginsAreByteIdentical) {
  REQUIRE_DEVICE();
  // The clearing margin travels in each ray (prepare kernel) and is applied by the shared
  // traversal: W1 with 2 cm LiDAR noise, Bresenham, RGB-D with quadratic depth noise, and a
  // correction + removal with noise.
  SensorModel lidar = SensorModel::autoFromCloud(0.0, 30.0);
  lidar.range_noise_m = 0.02;
  const auto w1 = simulatedW1(10);
  expectBackendsAgree(w1, paramsFor(Backend::kCuda, 0.05), lidar, "W1 (10 scans) 2 cm noise");
  MapParams p = paramsFor(Backend::kCuda, 0.05);
  p.raycast = RayCast::kBresenham;
  expectBackendsAgree(w1, p, lidar, "W1 (10 scans) 2 cm noise, bresenham");
  SensorModel depth = SensorModel::autoFromCloud();
  depth.range_noise_quadratic_per_m = 0.0015;
  expectBackendsAgree(rgbdFrames(), paramsFor(Backend::kCuda, 0.03), depth,
                      "rgbd 3 cm, 1.5 mm r^2 noise");
  expectCorrectionAgrees(rgbdFrames(), paramsFor(Backend::kCuda, 0.03), depth, {2, 3, 4},
                         "rgbd frames with noise");
}

}  // namespace
}  // namespace fragg
