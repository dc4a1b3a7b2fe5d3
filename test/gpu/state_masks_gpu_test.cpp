// The state-mask layer (issue 34 items 1 and 2) on the CUDA backend against the CPU backend:
// after every scan of a drive (both apply kernels, a pool small enough to evict and upload
// again), after each named edit and after paging, the masks the host reads are byte-identical
// to the CPU backend's and equal to the masks recomputed from the cells; the blocks listed as
// changed state per scan (BlockChange::kMasks, from the device's stamps) are the CPU's.
// Skipped without a device.
#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "../core/state_masks_check.h"
#include "../test_dir.h"
#include "bench/synthetic_lidar.h"
#include "fragg_map/internal/backend_factory.h"
#include "fragg_map/map.h"
#include "gpu_test_util.h"
#ifdef FRAGG_HAVE_STORE
#include "../paging/paging_scenes.h"
#include "fragg_map/store/page_stores.h"
#endif

namespace fragg::test {
namespace {

struct Input {
  PointCloud cloud;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
};

/// `scans` synthetic 180k-point LiDAR scans `step_m` apart, then the same back to the start.
std::vector<Input> outAndBack(int scans, double step_m) {
  bench::SyntheticLidarOptions o;
  o.step_m = step_m;
  bench::SyntheticLidar lidar(o);
  std::vector<Input> out;
  for (int i = 0; i < scans; ++i) {
    Scan s = lidar.scan(i);
    out.push_back({s.cloud, s.T_map_sensor});
  }
  for (int i = scans - 1; i >= 0; --i) {
    const Input back = out[static_cast<size_t>(i)];
    out.push_back(back);
  }
  return out;
}

struct KeyLess {
  bool operator()(const BlockKey& a, const BlockKey& b) const {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  }
};

/// The changed-block list with masks (Map::masksChangedSince) as a map from key to masks.
std::map<BlockKey, BlockStateMasks, KeyLess> changedMasksSince(const Map& map, uint64_t revision) {
  std::vector<BlockKey> keys;
  std::vector<BlockStateMasks> masks;
  EXPECT_TRUE(map.masksChangedSince(revision, &keys, &masks));
  std::map<BlockKey, BlockStateMasks, KeyLess> out;
  for (size_t i = 0; i < keys.size(); ++i) EXPECT_TRUE(out.emplace(keys[i], masks[i]).second);
  return out;
}

/// The blocks `map` lists as changed state after `revision`.
std::set<BlockKey, KeyLess> changedSince(const Map& map, uint64_t revision) {
  const std::vector<BlockKey> keys = map.changedBlocksSince(revision, BlockChange::kMasks);
  return std::set<BlockKey, KeyLess>(keys.begin(), keys.end());
}

MapParams paramsFor(Backend b, double res) {
  MapParams p;
  p.resolution_m = res;
  p.backend = b;
  return p;
}

/// The CUDA map's masks (host view, after its write-back) byte-identical to the CPU map's both
/// ways, and equal to the reference recomputed from its cells.
void expectSameMasks(const Map& cpu, const Map& gpu, const std::string& what) {
  ASSERT_STREQ(gpu.backendName(), "cuda") << gpu.backendReason();
  std::string first;
  EXPECT_EQ(cpu.blockCount(), gpu.blockCount()) << what;
  EXPECT_EQ(blocksWithOtherMasks(gpu, cpu, &first), 0u) << what << ": " << first;
  EXPECT_EQ(blocksWithOtherMasks(cpu, gpu, &first), 0u) << what << ": " << first;
  EXPECT_EQ(blocksWithStaleMasks(gpu, &first), 0u) << what << " (cuda): " << first;
  EXPECT_EQ(blocksWithStaleMasks(cpu, &first), 0u) << what << " (cpu): " << first;
}

/// Both apply kernels (a warp a slot, a thread block a slot) with a small pool: masks after
/// every scan.
void driveAndCompare(bool warp_per_slot) {
  const std::vector<Input> scans = outAndBack(8, 4.0);
  MapParams p = paramsFor(Backend::kCuda, 0.1);
  p.cuda.pool_max_bytes = size_t(12000) * test::kSlotBytes;  // fewer slots than the drive's blocks
  p.cuda.warp_per_slot_apply = warp_per_slot;
  Map gpu(p);
  p.backend = Backend::kCpu;
  Map cpu(p);
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, 20.0);
  InsertStats total;
  for (size_t i = 0; i < scans.size(); ++i) {
    const uint64_t revision = gpu.revision();
    ASSERT_EQ(cpu.revision(), revision);
    cpu.insert(scans[i].cloud, scans[i].T, sensor);
    total.add(gpu.insert(scans[i].cloud, scans[i].T, sensor));
    // Before anything syncs the host map: the CUDA map's list comes from its device pool
    // (compacted there) and its host log (blocks written back on eviction), and equals the CPU
    // map's, keys and masks.
    const auto device_list = changedMasksSince(gpu, revision);
    EXPECT_EQ(device_list.size(), changedMasksSince(cpu, revision).size()) << "scan " << i;
    EXPECT_TRUE(device_list == changedMasksSince(cpu, revision)) << "scan " << i;
    expectSameMasks(cpu, gpu, "scan " + std::to_string(i));
    const auto listed = changedSince(gpu, revision);
    EXPECT_EQ(listed, changedSince(cpu, revision)) << "blocks listed as changed, scan " << i;
    EXPECT_FALSE(listed.empty()) << "scan " << i;
  }
  // Over the whole drive (blocks evicted, written back and uploaded again on the way).
  EXPECT_EQ(changedSince(gpu, 0), changedSince(cpu, 0));
  EXPECT_GT(total.blocks_evicted, 1000u) << "the pool never evicted";
  EXPECT_GT(total.blocks_uploaded, 1000u) << "no block went up again";
}

TEST(StateMasksGpuTest, DriveWarpPerSlotApplyIsByteIdentical) {
  REQUIRE_DEVICE();
  driveAndCompare(true);
}

TEST(StateMasksGpuTest, DriveBlockPerSlotApplyIsByteIdentical) {
  REQUIRE_DEVICE();
  driveAndCompare(false);
}

// Map::hostBlockView (the server's paced output shares): on a CUDA map it writes nothing back,
// so the device's changes since the last blockView() are not in it; after a blockView() it holds
// the same blocks and masks as blockView().
TEST(StateMasksGpuTest, HostBlockViewLagsTheDeviceUntilAWriteBack) {
  REQUIRE_DEVICE();
  const std::vector<Input> scans = outAndBack(3, 0.5);
  Map gpu(paramsFor(Backend::kCuda, 0.05));
  ASSERT_STREQ(gpu.backendName(), "cuda") << gpu.backendReason();
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, 30.0);
  gpu.insert(scans[0].cloud, scans[0].T, sensor);
  const size_t synced = gpu.blockView().size();  // written back
  EXPECT_EQ(gpu.hostBlockView().size(), synced);
  gpu.insert(scans[1].cloud, scans[1].T, sensor);
  const size_t host_before = gpu.hostBlockView().size();
  const BlockView all = gpu.blockView();
  EXPECT_LE(host_before, all.size());
  EXPECT_GT(all.size(), synced) << "the second scan made blocks";
  const BlockView host = gpu.hostBlockView();
  ASSERT_EQ(host.size(), all.size());
  size_t differ = 0;
  all.forEach([&](const BlockKey& key, const Block&) {
    const BlockStateMasks* a = all.findMasks(key);
    const BlockStateMasks* h = host.findMasks(key);
    if (!a || !h || !(*a == *h)) ++differ;
  });
  EXPECT_EQ(differ, 0u);
}

// A hostBlockView() pins the host's blocks (host_view_gate.h): with device changes pending, the
// thread that holds one gets a logic_error from blockView() (the write-back would move the
// blocks under its own view) and the map stays as it was; once the view is gone the write-back
// runs and the host shows the device's blocks. (Another thread's write-back waits for the view
// instead: HostViewGate's own tests.)
TEST(StateMasksGpuTest, AWriteBackUnderThisThreadsHostViewIsRefused) {
  REQUIRE_DEVICE();
  const std::vector<Input> scans = outAndBack(2, 0.5);
  Map gpu(paramsFor(Backend::kCuda, 0.05));
  ASSERT_STREQ(gpu.backendName(), "cuda") << gpu.backendReason();
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, 30.0);
  gpu.insert(scans[0].cloud, scans[0].T, sensor);
  gpu.insert(scans[1].cloud, scans[1].T, sensor);
  ASSERT_TRUE(gpu.deviceChangesPending());
  size_t host_size = 0;
  {
    const BlockView host = gpu.hostBlockView();
    host_size = host.size();
    EXPECT_THROW((void)gpu.blockView(), std::logic_error);
    EXPECT_TRUE(gpu.deviceChangesPending()) << "written back under the view";
    EXPECT_EQ(host.size(), host_size);
  }
  const BlockView all = gpu.blockView();
  EXPECT_FALSE(gpu.deviceChangesPending());
  EXPECT_GE(all.size(), host_size);
  EXPECT_EQ(gpu.hostBlockView().size(), all.size());
}

// Map::writeBackSome (the frontier mirror's write-back in pieces, each under the write lock):
// pieces until none is left give the host the same blocks, cells, masks and stamps as one
// whole write-back (blockView) of the same scans on another CUDA map.
TEST(StateMasksGpuTest, AWriteBackInPiecesEqualsOneWholeWriteBack) {
  REQUIRE_DEVICE();
  const std::vector<Input> scans = outAndBack(3, 0.5);
  Map pieces(paramsFor(Backend::kCuda, 0.05));
  Map whole(paramsFor(Backend::kCuda, 0.05));
  ASSERT_STREQ(pieces.backendName(), "cuda") << pieces.backendReason();
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, 30.0);
  for (size_t i = 0; i < 2; ++i) {
    pieces.insert(scans[i].cloud, scans[i].T, sensor);
    whole.insert(scans[i].cloud, scans[i].T, sensor);
  }
  EXPECT_TRUE(pieces.deviceChangesPending());
  size_t calls = 0;
  while (pieces.writeBackSome(500)) ASSERT_LT(++calls, 100000u);
  EXPECT_GT(calls, 2u) << "the scans changed fewer than 1,500 blocks";
  EXPECT_FALSE(pieces.deviceChangesPending());
  EXPECT_FALSE(pieces.writeBackSome(500));
  const BlockView host = pieces.hostBlockView();
  const BlockView all = whole.blockView();
  ASSERT_EQ(host.size(), all.size());
  size_t differ = 0;
  all.forEach([&](const BlockKey& key, const Block& block) {
    const Block* h = host.findBlock(key);
    if (!h || std::memcmp(h, &block, sizeof(Block)) != 0 ||
        !(*host.findMasks(key) == *all.findMasks(key)))
      ++differ;
  });
  EXPECT_EQ(differ, 0u);
  for (const BlockChange what : {BlockChange::kAny, BlockChange::kMasks, BlockChange::kOccupied})
    EXPECT_EQ(host.changedSince(0, what).size(), all.changedSince(0, what).size());
}

TEST(StateMasksGpuTest, NamedEditsAreByteIdentical) {
  REQUIRE_DEVICE();
  const std::vector<Input> scans = outAndBack(3, 2.0);
  MapParams p = paramsFor(Backend::kCuda, 0.1);
  p.scans.keep = true;
  Map gpu(p);
  p.backend = Backend::kCpu;
  Map cpu(p);
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, 30.0);
  auto both = [&](const std::function<void(Map&)>& edit, const std::string& what) {
    edit(cpu);
    edit(gpu);
    expectSameMasks(cpu, gpu, what);
  };
  auto insert = [&](size_t i) {
    return [&, i](Map& m) { m.insert(scans[i].cloud, scans[i].T, sensor); };
  };
  both(insert(0), "scan 0");
  both(insert(1), "scan 1");
  both([](Map& m) { m.remove(0); }, "remove");
  both(insert(2), "scan 2");
  Eigen::Isometry3d moved = scans[2].T;
  moved.translation() += Eigen::Vector3d(0.13, -0.07, 0.02);
  both([&](Map& m) { m.correctPoses({{2, moved}}); }, "correctPoses");
  const Eigen::Vector3d o = scans[1].T.translation();
  both(
      [&](Map& m) {
        m.clearBox(o - Eigen::Vector3d(3.03, 4.1, 1.0), o + Eigen::Vector3d(2, 1, 1));
      },
      "clearBox");
  both(insert(3), "scan 3 after clearBox");  // the edited blocks go up again
  both(
      [&](Map& m) {
        m.writeCells([&](CellWriter& w) {
          const VoxelKey k = m.keyOf(o + Eigen::Vector3d(0.5, 0.5, 0.0));
          w.fillCube(k, 12, m.model().max_fx);
        });
      },
      "writeCells");
  Map cut_cpu = cpu.truncate(o, o + Eigen::Vector3d(20, 20, 5));
  Map cut_gpu = gpu.truncate(o, o + Eigen::Vector3d(20, 20, 5));
  expectSameMasks(cpu, gpu, "truncate");
  std::string first;
  EXPECT_EQ(blocksWithOtherMasks(cut_cpu, cut_gpu, &first), 0u) << "truncated part: " << first;
  EXPECT_EQ(blocksWithStaleMasks(cut_gpu, &first), 0u) << "truncated part: " << first;
  both(
      [&](Map& m) {
        (void)m.merge(m.backendName() == std::string("cuda") ? cut_gpu : cut_cpu, MergeMode::kAdd);
      },
      "merge");
  both(insert(4), "scan 4 after merge");
  const std::string path = testDir() + "/state_masks_gpu.fgm";
  gpu.save(path);
  Map loaded = Map::load(path, Backend::kCuda);
  ASSERT_STREQ(loaded.backendName(), "cuda") << loaded.backendReason();
  EXPECT_EQ(blocksWithOtherMasks(loaded, cpu, &first), 0u) << "load: " << first;
  loaded.insert(scans[5].cloud, scans[5].T, sensor);
  cpu.insert(scans[5].cloud, scans[5].T, sensor);
  expectSameMasks(cpu, loaded, "scan 5 after load");
  both([](Map& m) { m.reset(); }, "reset");
  both(insert(0), "scan 0 after reset");
}

#ifdef FRAGG_HAVE_STORE
TEST(StateMasksGpuTest, PagedDriveIsByteIdentical) {
  REQUIRE_DEVICE();
  const std::string dir = testDir();
  Map gpu(corridorParams(Backend::kCuda)), cpu(corridorParams(Backend::kCpu));
  // 12 MB: a corridor scan needs up to ~3,660 blocks resident at once on the device (~8.5 MB
  // counted; 2 MB, the old figure, was refused as too small once the budget became a hard
  // limit), and the corridor's 8,359 blocks still page out and back in.
  gpu.attachPageStore(openPageStore(dir + "/map.db", false), corridorBudget(12.0, 5));
  constexpr int kScans = 60;
  for (int i = 0; i < kScans; ++i) {
    const Eigen::Isometry3d T = corridorPose(i, kScans);
    gpu.insert(corridorScan(T), T, corridorSensor());
    cpu.insert(corridorScan(T), T, corridorSensor());
    std::string first;
    ASSERT_EQ(blocksWithStaleMasks(gpu, &first), 0u) << "scan " << i << ": " << first;
  }
  EXPECT_GT(gpu.pagingStats().pages_read, 50u);
  gpu.ensureAllResident();
  expectSameMasks(cpu, gpu, "paged drive, all resident");
}
#endif

}  // namespace
}  // namespace fragg::test
