// Dynamic mapping (both void rules) with out-of-core paging on the CUDA backend (label gpu;
// skipped without a device): the corridor drive with a person walking in it, built on CUDA
// with a small RAM budget, equals the CPU build in memory cell for cell, and every scan
// classifies the same hits as dynamic. The void tests read blocks around the ones the rays
// reach (the window one block larger); blocks paged out there must be read back, not taken as
// never observed (the CPU's counterpart: test/paging/dynamic_paging_test.cpp).
#include <gtest/gtest.h>

#include <string>

#include "../paging/dynamic_corridor.h"
#include "../test_dir.h"
#include "fragg_map/internal/backend_factory.h"
#include "fragg_map/store/page_stores.h"

namespace fragg::test {
namespace {

constexpr int kScans = 40;

#define REQUIRE_DEVICE()                                                     \
  do {                                                                       \
    std::string why;                                                         \
    if (cudaDeviceName(0, &why).empty()) GTEST_SKIP() << "skipped: " << why; \
  } while (0)

void expectCudaPagedEqualsCpuInMemory(VoidSpaceRule rule) {
  const std::string dir = testDir();
  Map cpu(dynamicCorridorParams(rule, Backend::kCpu));
  Map cuda(dynamicCorridorParams(rule, Backend::kCuda));
  ASSERT_STREQ(cuda.backendName(), "cuda");
  cuda.attachPageStore(openPageStore(dir + "/map.db", false),
                       corridorBudget(12.0, 7));  // room for a scan on the device and its ring
  uint64_t dynamic_hits = 0;
  for (int i = 0; i < kScans; ++i) {
    const Eigen::Isometry3d T = corridorPose(i, kScans);
    const PointCloud cloud = walkerCorridorScan(i, kScans, T);
    const InsertStats on_cpu = cpu.insert(cloud, T, corridorSensor());
    const InsertStats on_cuda = cuda.insert(cloud, T, corridorSensor());
    ASSERT_EQ(on_cuda.rays_dynamic, on_cpu.rays_dynamic) << "scan " << i;
    dynamic_hits += on_cpu.rays_dynamic;
  }
  ASSERT_STREQ(cuda.backendName(), "cuda") << "fell back to the CPU";
  EXPECT_GT(cuda.pagingStats().pages_evicted, 500u) << "nothing paged out";
  EXPECT_GT(cuda.pagingStats().pages_read, 50u) << "the way back paged nothing in";
  EXPECT_GT(dynamic_hits, 100u) << "the rule was not exercised";
  cuda.ensureAllResident();
  std::string why;
  EXPECT_TRUE(sameBlocks(cuda, cpu, &why)) << why;
}

TEST(CudaDynamicPaging, PassThroughRuleEqualsTheCpuInMemory) {
  REQUIRE_DEVICE();
  expectCudaPagedEqualsCpuInMemory(VoidSpaceRule::kPassThrough);
}

TEST(CudaDynamicPaging, SurroundRuleEqualsTheCpuInMemory) {
  REQUIRE_DEVICE();
  expectCudaPagedEqualsCpuInMemory(VoidSpaceRule::kSurround);
}

}  // namespace
}  // namespace fragg::test
