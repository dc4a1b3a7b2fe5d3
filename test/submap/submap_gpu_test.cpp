// Sub-map edits on the CUDA backend against the CPU backend: the same truncations, merges and
// later insertions give the same cells, so every edit went through the device cache's
// invalidation (a stale device copy would be written back over the edit). Labelled `gpu`;
// skipped where there is no CUDA device.
#include <gtest/gtest.h>

#include <string>

#include "fragg_map/internal/backend_factory.h"
#include "submap_scenes.h"

namespace fragg {
namespace {

MapParams paramsFor(Backend backend) {
  MapParams p = test::cpuParams();
  p.backend = backend;
  return p;
}

void expectSame(const Map& cuda, const Map& cpu, const char* step) {
  std::string why;
  EXPECT_TRUE(test::sameCells(cuda, cpu, &why)) << step << ": " << why;
}

TEST(SubmapGpuTest, EditsThroughTheDeviceCacheMatchTheCpuBackend) {
  std::string why;
  if (cudaDeviceName(0, &why).empty()) GTEST_SKIP() << "skipped: " << why;
  Map cuda = test::roomMap(paramsFor(Backend::kCuda));
  Map cpu = test::roomMap(paramsFor(Backend::kCpu));
  ASSERT_STREQ(cuda.backendName(), "cuda");
  expectSame(cuda, cpu, "built");
  const PointCloud scan = test::roomScan(4.0, 1.0, 2.0, 16, 360);
  const Eigen::Vector3d lo(-0.7, -1.1, -0.4), hi(1.3, 0.9, 1.2);

  const Map sub_cuda = cuda.truncate(lo, hi, Backend::kCuda);
  const Map sub_cpu = cpu.truncate(lo, hi, Backend::kCpu);
  expectSame(cuda, cpu, "truncated");
  expectSame(sub_cuda, sub_cpu, "sub-maps");
  ASSERT_GT(sub_cpu.knownVoxelCount(), 1000u);
  // The next scan reaches into the truncated box: device copies must not come back.
  cuda.insert(scan, test::poseAt(5), test::lidar());
  cpu.insert(scan, test::poseAt(5), test::lidar());
  expectSame(cuda, cpu, "insert after truncate");

  cuda.merge(sub_cuda, MergeMode::kAdd);
  cpu.merge(sub_cpu, MergeMode::kAdd);
  expectSame(cuda, cpu, "merged");
  cuda.insert(scan, test::poseAt(6), test::lidar());
  cpu.insert(scan, test::poseAt(6), test::lidar());
  expectSame(cuda, cpu, "insert after merge");

  const Map far_cuda = cuda.truncateOutside(Eigen::Vector3d(1.0, 0.5, 0.3), 2.0, Backend::kCuda);
  const Map far_cpu = cpu.truncateOutside(Eigen::Vector3d(1.0, 0.5, 0.3), 2.0, Backend::kCpu);
  expectSame(cuda, cpu, "truncated outside");
  expectSame(far_cuda, far_cpu, "far sub-maps");
  cuda.insert(scan, test::poseAt(7), test::lidar());
  cpu.insert(scan, test::poseAt(7), test::lidar());
  expectSame(cuda, cpu, "insert after truncateOutside");

  Eigen::Isometry3d T_map_sub = Eigen::Isometry3d::Identity();
  T_map_sub.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  cuda.merge(far_cuda, MergeMode::kOverwrite, T_map_sub);
  cpu.merge(far_cpu, MergeMode::kOverwrite, T_map_sub);
  expectSame(cuda, cpu, "resampled merge");
  cuda.insert(scan, test::poseAt(8), test::lidar());
  cpu.insert(scan, test::poseAt(8), test::lidar());
  expectSame(cuda, cpu, "insert after resampled merge");
}

}  // namespace
}  // namespace fragg
