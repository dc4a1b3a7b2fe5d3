// Finite points at the ends of the float range (issue 39) through the CUDA backend: the cloud is
// inserted (never refused with "ray left the window table"), and the map is byte-identical to
// the CPU backend's, for the points at 5 and 20 cm with max range 20 m, 80 m and none,
// for rays cut into pieces, for a kept scan corrected and removed again, and for every input of
// the insertion fuzz target's committed corpus. Skipped without a CUDA device.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "../core/extreme_points.h"
#include "../core/same_map.h"
#include "../fuzz/insert_input.h"
#include "fragg_map/errors.h"
#include "fragg_map/internal/backend_factory.h"
#include "fragg_map/map.h"
#include "gpu_test_util.h"

namespace fragg {
namespace {

const std::vector<Eigen::Vector3f>& kExtremePoints = test::extremePoints();

/// A ring of points around the sensor (so the auto model is a LiDAR) and the extreme points.
PointCloud extremeCloud() {
  PointCloud c;
  for (int i = 0; i < 360; i += 3) {
    const float a = static_cast<float>(i) * 3.14159265f / 180.f;
    c.points_S.emplace_back(4.f * std::cos(a), 4.f * std::sin(a), 0.3f * std::sin(3.f * a));
  }
  for (const Eigen::Vector3f& p : kExtremePoints) c.points_S.push_back(p);
  return c;
}

MapParams paramsFor(Backend b, double res) {
  MapParams p;
  p.backend = b;
  p.resolution_m = res;
  return p;
}

TEST(ExtremePointsGpu, CudaMapsAreByteIdenticalToTheCpu) {
  REQUIRE_DEVICE();
  const PointCloud cloud = extremeCloud();
  for (double res : {0.05, 0.2}) {
    for (double max_range_m : {20.0, 80.0, -1.0}) {
      for (int piece_steps : {0, 64}) {
        SCOPED_TRACE(::testing::Message()
                     << "res " << res << " max range " << max_range_m << " pieces " << piece_steps);
        MapParams pc = paramsFor(Backend::kCpu, res), pg = paramsFor(Backend::kCuda, res);
        pg.cuda.ray_piece_steps = piece_steps;
        Map cpu(pc), gpu(pg);
        ASSERT_STREQ(gpu.backendName(), "cuda");
        const SensorModel sensor = SensorModel::autoFromCloud(0.0, max_range_m);
        // The sensor at the origin (starts on cell boundaries) and moved and turned.
        Eigen::Isometry3d moved = Eigen::Isometry3d::Identity();
        moved.translate(Eigen::Vector3d(0.37, -1.21, 0.4));
        moved.rotate(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
        for (const Eigen::Isometry3d& T : {Eigen::Isometry3d::Identity(), moved}) {
          const InsertStats a = cpu.insert(cloud, T, sensor);
          const InsertStats b = gpu.insert(cloud, T, sensor);
          EXPECT_EQ(a.rays_hit, b.rays_hit);
          EXPECT_EQ(a.rays_free_only, b.rays_free_only);
          EXPECT_EQ(a.dropped_invalid, b.dropped_invalid);
          EXPECT_EQ(a.cells_updated, b.cells_updated);
        }
        test::expectSameMap(cpu, gpu, "extreme points");
      }
    }
  }
}

TEST(ExtremePointsGpu, CorrectionAndRemovalAreByteIdentical) {
  REQUIRE_DEVICE();
  MapParams pc = paramsFor(Backend::kCpu, 0.05), pg = paramsFor(Backend::kCuda, 0.05);
  pc.scans.keep = pg.scans.keep = true;
  Map cpu(pc), gpu(pg);
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, 30.0);
  const PointCloud cloud = extremeCloud();
  Eigen::Isometry3d second = Eigen::Isometry3d::Identity();
  second.translate(Eigen::Vector3d(1.0, 0.5, 0.0));
  for (Map* m : {&cpu, &gpu}) {
    const InsertStats first = m->insert(cloud, Eigen::Isometry3d::Identity(), sensor);
    m->insert(cloud, second, sensor);
    Eigen::Isometry3d corrected = Eigen::Isometry3d::Identity();
    corrected.translate(Eigen::Vector3d(-0.2, 0.3, 0.1));
    m->correctPoses({{first.scan_id, corrected}});
    m->remove(first.scan_id);
  }
  test::expectSameMap(cpu, gpu, "corrected and removed");
}

TEST(ExtremePointsGpu, InsertionFuzzCorpusGivesTheCpusMaps) {
  // Each input of test/fuzz/corpus/insert (seeds and the fuzzer's finds) through both backends:
  // the same maps, or the same refusal.
  REQUIRE_DEVICE();
  namespace fs = std::filesystem;
  size_t inputs = 0, refused = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(FRAGG_FUZZ_CORPUS) / "insert")) {
    std::ifstream file(entry.path(), std::ios::binary);
    const std::vector<uint8_t> bytes(std::istreambuf_iterator<char>(file), {});
    SCOPED_TRACE(entry.path().filename().string());
    fuzz::InsertInput in = fuzz::decodeInsertInput(bytes.data(), bytes.size());
    const MapParams cpu_params = in.params;
    in.params.backend = Backend::kCuda;
    in.params.threads = 0;
    std::string cpu_error = "none", gpu_error = "none";
    std::unique_ptr<Map> cpu, gpu;
    try {
      cpu = std::make_unique<Map>(cpu_params);
      fuzz::runInsertInput(in, *cpu);
    } catch (const InvalidArgument& e) {
      cpu_error = e.what();
    }
    try {
      gpu = std::make_unique<Map>(in.params);
      fuzz::runInsertInput(in, *gpu);
    } catch (const InvalidArgument& e) {
      gpu_error = e.what();
    }
    EXPECT_EQ(cpu_error, gpu_error);
    if (cpu_error == "none" && gpu_error == "none") test::expectSameMap(*cpu, *gpu, "corpus");
    refused += cpu_error != "none" ? 1 : 0;
    ++inputs;
  }
  EXPECT_GE(inputs, 60u);
  std::printf("[gpu] insertion corpus: %zu inputs, %zu refused by both backends\n", inputs,
              refused);
}

}  // namespace
}  // namespace fragg
