// Map::freeBox (octomap_server's clear_bbx: the known cells in a box set to the lower clamp) on
// the CUDA backend: blocks resident on the device are written back and refreshed, so the map
// after the edit and after more scans is byte-identical to the CPU backend's. Skipped without a
// CUDA device.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <string>
#include <vector>

#include "../core/same_map.h"
#include "fragg_map/internal/backend_factory.h"
#include "fragg_map/map.h"
#include "gpu_test_util.h"

namespace fragg {
namespace {

/// A ring of walls 3-6 m around the sensor, wavy in height.
PointCloud ringCloud(float radius_m) {
  PointCloud c;
  for (int i = 0; i < 720; ++i) {
    const float a = static_cast<float>(i) * 3.14159265f / 360.f;
    for (int j = -4; j <= 4; ++j)
      c.points_S.emplace_back(radius_m * std::cos(a), radius_m * std::sin(a),
                              0.25f * j + 0.2f * std::sin(5.f * a));
  }
  return c;
}

TEST(FreeBoxGpu, FreedBoxesAndLaterScansAreByteIdenticalToTheCpu) {
  REQUIRE_DEVICE();
  MapParams pc, pg;
  pc.backend = Backend::kCpu;
  pg.backend = Backend::kCuda;
  pc.resolution_m = pg.resolution_m = 0.05;
  Map cpu(pc), gpu(pg);
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, 10.0);
  Eigen::Isometry3d moved = Eigen::Isometry3d::Identity();
  moved.translate(Eigen::Vector3d(0.8, -0.3, 0.1));
  for (Map* m : {&cpu, &gpu}) {
    m->insert(ringCloud(4.f), Eigen::Isometry3d::Identity(), sensor);
    m->insert(ringCloud(5.5f), moved, sensor);
  }
  const Eigen::Vector3d lo(2.0, -3.0, -0.6), hi(6.0, 3.0, 0.4);
  const uint64_t freed_cpu = cpu.freeBox(lo, hi);
  const uint64_t freed_gpu = gpu.freeBox(lo, hi);
  EXPECT_GT(freed_cpu, 0u);
  EXPECT_EQ(freed_cpu, freed_gpu);
  test::expectSameMap(cpu, gpu, "after freeBox");
  // The device must not keep a stale copy of a freed block: more scans over the box.
  for (Map* m : {&cpu, &gpu}) m->insert(ringCloud(3.5f), moved, sensor);
  test::expectSameMap(cpu, gpu, "freeBox, then a scan over the box");
}

}  // namespace
}  // namespace fragg
