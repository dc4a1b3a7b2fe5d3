// Out-of-core paging on the CUDA backend (label gpu; skipped without a device): the device
// cache sits on the host map and paging under it, so a paged CUDA build must equal the CPU
// build in memory, block for block, with the device pool large or tiny. The budget is a hard
// limit as on the CPU (the host map and the blocks that exist on the device only): the rays
// page in the regions they reach and create no block past the budget's room; a scan that
// cannot fit is refused with the map intact.
#include <gtest/gtest.h>

#include <string>

#include "../paging/paging_scenes.h"
#include "fragg_map/errors.h"
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

/// Returns the blocks the scans uploaded to the device; adds the blocks the device cache
/// evicted to `*evicted` when given.
uint64_t insertScans(Map& map, int from, int to, uint64_t* evicted = nullptr) {
  uint64_t uploaded = 0;
  for (int i = from; i < to; ++i) {
    const Eigen::Isometry3d T = corridorPose(i, kScans);
    const InsertStats s = map.insert(corridorScan(T), T, corridorSensor());
    uploaded += s.blocks_uploaded;
    if (evicted) *evicted += s.blocks_evicted;
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

/// A budget of `mb` (commits every 7 scans). The corridor's scans need up to ~3,660 blocks at
/// once on the device (the frustum's blocks and the new ones; 3,658 on the CPU map in memory),
/// ~8.5 MB at Pager::reservedBlockBytes(): 12 MB leaves room for the regions around them and
/// still pages (the corridor is 8,359 blocks).
PagingPolicy budgetOf(double mb) {
  PagingPolicy p;
  p.budget_mb = mb;
  p.radius_m = 4.0;
  p.commit_every_scans = 7;
  p.commit_every_s = 0;
  return p;
}

void pagedCudaBuildMatchesCpu(const std::string& store_path, size_t pool_max_bytes,
                              double budget_mb) {
  MapParams params = corridorParams(Backend::kCuda);
  params.cuda.pool_max_bytes = pool_max_bytes;
  Map paged(params);
  ASSERT_STREQ(paged.backendName(), "cuda");
  paged.attachPageStore(openPageStore(store_path, false), budgetOf(budget_mb));
  uint64_t uploaded = 0, evicted = 0;
  for (int i = 0; i < kScans; ++i) {
    uploaded += insertScans(paged, i, i + 1, &evicted);
    // The peak counts the host map and the device's own blocks at every page-in and after
    // every scan: the most the map held, not a sample.
    const PagingStats st = paged.pagingStats();
    ASSERT_LE(st.peak_resident_blocks, st.budget_blocks) << "scan " << i;
    ASSERT_LE(st.peak_counted_bytes, st.budget_bytes) << "scan " << i;
  }
  // Every scan ran on the device (no fall back to the CPU: the pool held each scan's blocks).
  EXPECT_STREQ(paged.backendName(), "cuda");
  const PagingStats st = paged.pagingStats();
  EXPECT_GT(st.pages_evicted, 1000u);
  EXPECT_GT(st.pages_read, 100u);
  // The regions the rays pass through are read back before the ray pass (Map::pageInAhead,
  // walked on the host): a pass that stops on a paged-out region is the exception.
  EXPECT_GT(st.scans_read_ahead, 0u);
  EXPECT_GT(st.blocks_read_ahead, st.blocks_read_in_scan)
      << "stops in scans " << st.stops_in_scan << ", read-ahead scans " << st.scans_read_ahead;
  // Paging out drops only the leaving blocks' device copies: with a pool that holds the map,
  // a block is uploaded only after it came back from the store (emptying the cache at every
  // paging round uploaded every block of the scans again).
  if (pool_max_bytes == 0) {
    EXPECT_LE(uploaded, st.pages_read);
  } else {
    EXPECT_GT(evicted, 0u) << "the pool held every resident block: not a tiny pool";
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
  pagedCudaBuildMatchesCpu(testDir() + "/map.db", 0, 12.0);
}

TEST(CudaPaging, TinyDevicePoolAndPagingTogether) {
  REQUIRE_DEVICE();
  // A pool of 10 MiB (~4,400 slots): one scan's blocks (~3,660) fit, the resident map (up to
  // 6,295 blocks under 14 MB) does not, so the device cache evicts to the host while the host
  // pages to the store.
  pagedCudaBuildMatchesCpu(testDir() + "/map.db", size_t{10} << 20, 14.0);
}

TEST(CudaPaging, AScanThatCannotFitTheBudgetIsRefusedAndTheMapStaysAsItWas) {
  REQUIRE_DEVICE();
  Map paged(corridorParams(Backend::kCuda));
  // 0.25 MB: about 110 blocks, fewer than one corridor scan creates.
  paged.attachPageStore(openPageStore(testDir() + "/map.db", false), budgetOf(0.25));
  const Eigen::Isometry3d T = corridorPose(0, kScans);
  try {
    paged.insert(corridorScan(T), T, corridorSensor());
    ADD_FAILURE() << "a scan larger than the budget was integrated";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("raise the budget"), std::string::npos) << e.what();
  }
  EXPECT_STREQ(paged.backendName(), "cuda");
  EXPECT_EQ(paged.scanCount(), 0u);
  EXPECT_EQ(paged.blockCount(), 0u);
  EXPECT_LE(paged.pagingStats().peak_resident_blocks, paged.pagingStats().budget_blocks);

  // A scan that fits goes in afterwards, on the device, as it would into a map without paging.
  const PointCloud few = twoPointScan(T);
  paged.insert(few, T, corridorSensor());
  Map memory(corridorParams(Backend::kCpu));
  memory.insert(few, T, corridorSensor());
  EXPECT_STREQ(paged.backendName(), "cuda");
  EXPECT_EQ(paged.scanCount(), 1u);
  std::string why;
  EXPECT_TRUE(sameBlocks(paged, memory, &why)) << why;
}

TEST(CudaPaging, ContinuedOnTheDeviceAndQueriedAfterPagingOut) {
  REQUIRE_DEVICE();
  const std::string path = testDir() + "/map.db";
  {
    Map first(corridorParams(Backend::kCuda));
    first.attachPageStore(openPageStore(path, false), budgetOf(12.0));
    insertScans(first, 0, kScans / 2);
  }
  Map again = Map::openPageStore(openPageStore(path, false), corridorParams(Backend::kCuda),
                                 budgetOf(12.0));
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
