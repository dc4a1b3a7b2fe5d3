// Out-of-core paging on the CUDA backend (label gpu; skipped without a device): the device
// cache sits on the host map and paging under it, so a paged CUDA build must equal the CPU
// build in memory, block for block, with the device pool large or tiny.
#include <gtest/gtest.h>

#include <string>

#include "../paging/paging_scenes.h"
#include "fragg_map/internal/backend_factory.h"
#include "fragg_map/store/page_stores.h"

namespace fragg::test {
namespace {

constexpr int kScans = 80;

#define REQUIRE_DEVICE()                                                     \
  do {                                                                       \
    std::string why;                                                         \
    if (cudaDeviceName(0, &why).empty()) GTEST_SKIP() << "skipped: " << why; \
  } while (0)

/// Returns the blocks the scans uploaded to the device.
uint64_t insertScans(Map& map, int from, int to) {
  uint64_t uploaded = 0;
  for (int i = from; i < to; ++i) {
    const Eigen::Isometry3d T = corridorPose(i, kScans);
    uploaded += map.insert(corridorScan(T), T, corridorSensor()).blocks_uploaded;
  }
  return uploaded;
}

const Map& cpuInMemory() {
  static const Map map = [] {
    Map m(corridorParams(Backend::kCpu));
    insertScans(m, 0, kScans);
    return m;
  }();
  return map;
}

PagingPolicy smallBudget() {
  PagingPolicy p;
  p.budget_mb = 3.0;
  p.radius_m = 4.0;
  p.commit_every_scans = 7;
  p.commit_every_s = 0;
  return p;
}

void pagedCudaBuildMatchesCpu(const std::string& store_path, size_t pool_max_bytes) {
  MapParams params = corridorParams(Backend::kCuda);
  params.cuda.pool_max_bytes = pool_max_bytes;
  Map paged(params);
  ASSERT_STREQ(paged.backendName(), "cuda");
  paged.attachPageStore(openPageStore(store_path, false), smallBudget());
  uint64_t uploaded = 0;
  for (int i = 0; i < kScans; ++i) {
    uploaded += insertScans(paged, i, i + 1);
    ASSERT_LE(paged.pagingStats().resident_blocks, paged.pagingStats().budget_blocks) << i;
  }
  const PagingStats st = paged.pagingStats();
  EXPECT_GT(st.pages_evicted, 1000u);
  EXPECT_GT(st.pages_read, 100u);
  // Paging out drops only the leaving blocks' device copies: with a pool that holds the map,
  // a block is uploaded only after it came back from the store (emptying the cache at every
  // paging round uploaded every block of the scans again).
  if (pool_max_bytes == 0) {
    EXPECT_LE(uploaded, st.pages_read);
  }
  paged.commitPages();
  std::string why;
  const Map from_store = Map::loadPageStore(*openPageStore(store_path, true));
  EXPECT_TRUE(sameBlocks(from_store, cpuInMemory(), &why)) << why;
  paged.ensureAllResident();
  EXPECT_TRUE(sameBlocks(paged, cpuInMemory(), &why)) << why;
}

TEST(CudaPaging, PagedCudaBuildIsByteIdenticalToTheCpuInMemoryBuild) {
  REQUIRE_DEVICE();
  pagedCudaBuildMatchesCpu(testDir() + "/map.db", 0);
}

TEST(CudaPaging, TinyDevicePoolAndPagingTogether) {
  REQUIRE_DEVICE();
  // A pool of 4 MiB: the device cache evicts to the host while the host pages to the store.
  pagedCudaBuildMatchesCpu(testDir() + "/map.db", size_t{4} << 20);
}

TEST(CudaPaging, ContinuedOnTheDeviceAndQueriedAfterPagingOut) {
  REQUIRE_DEVICE();
  const std::string path = testDir() + "/map.db";
  {
    Map first(corridorParams(Backend::kCuda));
    first.attachPageStore(openPageStore(path, false), smallBudget());
    insertScans(first, 0, kScans / 2);
  }
  Map again =
      Map::openPageStore(openPageStore(path, false), corridorParams(Backend::kCuda), smallBudget());
  ASSERT_EQ(again.scanCount(), static_cast<size_t>(kScans / 2));
  // Near the start (paged out): every cell there as in the CPU map of the same scans.
  Map cpu_half(corridorParams(Backend::kCpu));
  insertScans(cpu_half, 0, kScans / 2);
  for (double x = 0.05; x < 2.0; x += 0.1)
    for (double y = -4.05; y < 4.1; y += 0.1) {
      const Eigen::Vector3d p(x, y, 0.05);
      EXPECT_EQ(again.query(p), cpu_half.query(p)) << p.transpose();
    }
  insertScans(again, kScans / 2, kScans);
  again.ensureAllResident();
  std::string why;
  EXPECT_TRUE(sameBlocks(again, cpuInMemory(), &why)) << why;
}

}  // namespace
}  // namespace fragg::test
