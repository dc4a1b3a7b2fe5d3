// The state-mask layer (issue 34 item 1) on the CPU backend: stateMasksOf() as the reference,
// and the masks every writer keeps equal to it (insertion, removal, correction, each named
// edit, save / load, reset).
#include "fragg_map/state_masks.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <utility>

#include "fragg_map/map.h"
#include "state_masks_check.h"
#include "test_scenes.h"

namespace fragg::test {
namespace {

MapParams keeping() {
  MapParams p;
  p.resolution_m = 0.05;
  p.backend = Backend::kCpu;
  p.scans.keep = true;
  return p;
}

PointCloud room() { return roomScan(4.0, 1.0, 2.0, 16, 360); }

/// The i-th pose of a short walk through the room (0.3 m steps, a few degrees of yaw).
Eigen::Isometry3d poseAt(int i, double dx_m = 0.0, double dyaw_rad = 0.0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.3 * i + dx_m, 0.1 * i, 0.02);
  T.linear() = Eigen::AngleAxisd(0.05 * i + dyaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T;
}

SensorModel lidar() { return SensorModel::spinningLidar(-0.6, 0.6, 0.0, 10.0); }

/// Occupied and free cells over the map's masks.
std::pair<size_t, size_t> maskCounts(const Map& map) {
  size_t occupied = 0, free = 0;
  const BlockView view = map.blockView();
  view.forEach([&](const BlockKey& key, const Block&) {
    occupied += view.findMasks(key)->occupiedCount();
    free += view.findMasks(key)->freeCount();
  });
  return {occupied, free};
}

/// Every block's masks equal the reference; the map holds cells of both known states.
void expectMasksCurrent(const Map& map, const std::string& after) {
  std::string first;
  EXPECT_EQ(blocksWithStaleMasks(map, &first), 0u) << "after " << after << ": " << first;
  const auto [occupied, free] = maskCounts(map);
  EXPECT_GT(occupied, 100u) << after;
  EXPECT_GT(free, 1000u) << after;
}

TEST(StateMasksTest, ReferenceFollowsTheModelsThresholds) {
  const OccupancyModel model = OccupancyModel::fromParams(OccupancyParams());
  Block block;                                                // every cell unobserved
  block.cells[0].log_odds_fx = model.max_fx;                  // occupied
  block.cells[1].log_odds_fx = model.min_fx;                  // free
  block.cells[63].log_odds_fx = 0;                            // observed, in the band: unknown
  block.cells[64].log_odds_fx = model.occupied_above_fx;      // on the threshold: unknown
  block.cells[65].log_odds_fx = model.occupied_above_fx + 1;  // occupied
  block.cells[511].log_odds_fx = model.free_below_fx - 1;     // free
  block.cells[510].log_odds_fx = model.free_below_fx;         // on the threshold: unknown
  const BlockStateMasks m = stateMasksOf(block, model);
  EXPECT_EQ(m.occupied[0], uint64_t{1});
  EXPECT_EQ(m.free[0], uint64_t{2});
  EXPECT_EQ(m.occupied[1], uint64_t{1} << 1);
  EXPECT_EQ(m.free[1], uint64_t{0});
  EXPECT_EQ(m.free[7], uint64_t{1} << 63);
  EXPECT_EQ(m.occupiedCount(), 2);
  EXPECT_EQ(m.freeCount(), 2);
  EXPECT_TRUE(m.anyUnknown());
  for (int c : {0, 65}) EXPECT_EQ(m.state(c), CellState::kOccupied) << c;
  for (int c : {1, 511}) EXPECT_EQ(m.state(c), CellState::kFree) << c;
  for (int c : {2, 63, 64, 510}) EXPECT_EQ(m.state(c), CellState::kUnknown) << c;
  for (int c = 0; c < kCellsPerBlock; ++c) EXPECT_EQ(m.state(c), model.state(block.cells[c])) << c;

  BlockStateMasks set;
  for (int c = 0; c < kCellsPerBlock; ++c) set.set(c, model.state(block.cells[c]));
  EXPECT_EQ(set, m);
  set.set(0, CellState::kFree);
  EXPECT_NE(set, m);
  EXPECT_EQ(set.state(0), CellState::kFree);
}

TEST(StateMasksTest, InsertionKeepsMasksCurrentAfterEveryScan) {
  Map map(keeping());
  for (int i = 0; i < 5; ++i) {
    map.insert(room(), poseAt(i), lidar());
    expectMasksCurrent(map, "scan " + std::to_string(i));
  }
}

// On a CPU map nothing waits for a write-back: the host's view (the server's paced output
// shares read it) is blockView(), block for block and mask for mask.
TEST(StateMasksTest, HostBlockViewOfACpuMapIsItsBlockView) {
  Map map(keeping());
  for (int i = 0; i < 3; ++i) map.insert(room(), poseAt(i), lidar());
  const BlockView all = map.blockView();
  const BlockView host = map.hostBlockView();
  ASSERT_GT(all.size(), 0u);
  ASSERT_EQ(host.size(), all.size());
  size_t differ = 0;
  all.forEach([&](const BlockKey& key, const Block& block) {
    const Block* h = host.findBlock(key);
    if (h != &block || !(*host.findMasks(key) == *all.findMasks(key))) ++differ;
  });
  EXPECT_EQ(differ, 0u);
}

TEST(StateMasksTest, RemovalAndCorrectionKeepMasksCurrent) {
  Map map(keeping());
  for (int i = 0; i < 4; ++i) map.insert(room(), poseAt(i), lidar());
  const auto before = maskCounts(map);
  map.remove(1);
  expectMasksCurrent(map, "remove");
  EXPECT_NE(maskCounts(map), before) << "the removal changed no state";
  map.correctPoses({{0, poseAt(0, 0.07, 0.02)}, {2, poseAt(2, -0.05, 0.01)}});
  expectMasksCurrent(map, "correctPoses");
}

TEST(StateMasksTest, FreeBoxKeepsMasksCurrentAndListsItsBlocks) {
  Map map(keeping());
  for (int i = 0; i < 3; ++i) map.insert(room(), poseAt(i), lidar());
  // An occupied cell of a wall; the box around it cuts blocks (not on block bounds).
  VoxelKey wall{0, 0, 0};
  bool found = false;
  map.forEachBlock([&](const BlockKey& key, const Block& block) {
    for (int c = 0; c < kCellsPerBlock && !found; ++c)
      if (map.state(block.cells[c]) == CellState::kOccupied) {
        wall = voxelKeyOf(key, c);
        found = true;
      }
  });
  ASSERT_TRUE(found);
  const Eigen::Vector3d p = map.centerOf(wall);
  const uint64_t before = map.revision();
  EXPECT_GT(map.freeBox(p - Eigen::Vector3d(0.33, 0.41, 0.27), p + Eigen::Vector3d(0.3, 0.3, 0.3)),
            0u);
  expectMasksCurrent(map, "freeBox");
  EXPECT_EQ(map.query(p), CellState::kFree);
  const std::vector<BlockKey> listed = map.changedBlocksSince(before, BlockChange::kMasks);
  EXPECT_NE(std::find(listed.begin(), listed.end(), blockKeyOf(wall)), listed.end())
      << "the freed wall's block is not in the kMasks list";
}

TEST(StateMasksTest, ClearBoxAndWriteCellsKeepMasksCurrent) {
  Map map(keeping());
  for (int i = 0; i < 3; ++i) map.insert(room(), poseAt(i), lidar());
  // A box that cuts blocks (not on block bounds) on walls and free space.
  map.clearBox(Eigen::Vector3d(-1.03, -4.2, -1.2), Eigen::Vector3d(0.61, 0.33, 0.47));
  expectMasksCurrent(map, "clearBox");
  EXPECT_EQ(map.query(Eigen::Vector3d(0.0, -4.0, 0.0)), CellState::kUnknown);

  const OccupancyModel& model = map.model();
  const VoxelKey lone{400, 400, 400};  // far from everything: a new block
  const VoxelKey wall = map.keyOf(Eigen::Vector3d(3.99, 0.5, 0.5));
  map.writeCells([&](CellWriter& w) {
    Cell occupied;
    occupied.log_odds_fx = model.max_fx;
    w.set(lone, occupied);
    w.set(wall, Cell());                                    // observed -> unknown
    w.fillCube(VoxelKey{-10, -10, -10}, 11, model.min_fx);  // spans 27 blocks
  });
  expectMasksCurrent(map, "writeCells");
  ASSERT_NE(map.findMasks(blockKeyOf(lone)), nullptr);
  EXPECT_EQ(map.findMasks(blockKeyOf(lone))->state(cellIndexOf(lone)), CellState::kOccupied);
  EXPECT_EQ(map.findMasks(blockKeyOf(lone))->occupiedCount(), 1);
  EXPECT_EQ(map.findMasks(blockKeyOf(wall))->state(cellIndexOf(wall)), CellState::kUnknown);
  EXPECT_EQ(map.findMasks(blockKeyOf(VoxelKey{-1, -1, -1}))->freeCount(), kCellsPerBlock);
}

TEST(StateMasksTest, SubMapEditsKeepMasksCurrentInBothMaps) {
  Map map(keeping());
  for (int i = 0; i < 3; ++i) map.insert(room(), poseAt(i), lidar());
  const Eigen::Vector3d lo(-4.5, -4.5, -1.5), hi(1.13, 4.5, 2.5);

  const Map extracted = map.extract(lo, hi);
  expectMasksCurrent(extracted, "extract (sub-map)");
  const Map outside = map.extractOutside(Eigen::Vector3d(0.5, 0.0, 0.0), 2.7);
  expectMasksCurrent(outside, "extractOutside (sub-map)");

  Map truncated = map.truncate(Eigen::Vector3d(2.0, -4.5, -1.5), hi + Eigen::Vector3d(5, 0, 0));
  expectMasksCurrent(truncated, "truncate (sub-map)");
  expectMasksCurrent(map, "truncate");
  Map beyond = map.truncateOutside(Eigen::Vector3d(0.5, 0.0, 0.0), 3.3);
  expectMasksCurrent(beyond, "truncateOutside (sub-map)");
  expectMasksCurrent(map, "truncateOutside");

  // Merges: exact shifts (overwrite and add) and a resampling pose.
  map.merge(truncated, MergeMode::kOverwrite);
  expectMasksCurrent(map, "merge (overwrite)");
  map.merge(beyond, MergeMode::kAdd);
  expectMasksCurrent(map, "merge (add)");
  Eigen::Isometry3d T_map_sub = Eigen::Isometry3d::Identity();
  T_map_sub.translation() = Eigen::Vector3d(0.31, -0.17, 0.0);
  T_map_sub.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  map.merge(extracted, MergeMode::kAdd, T_map_sub);
  expectMasksCurrent(map, "merge (resampled)");
}

TEST(StateMasksTest, SaveLoadAndResetKeepMasksCurrent) {
  Map map(keeping());
  for (int i = 0; i < 3; ++i) map.insert(room(), poseAt(i), lidar());
  const std::string path = std::string(FRAGG_TEST_TMP) + "/state_masks.fgm";
  map.save(path);
  const Map loaded = Map::load(path, Backend::kCpu);
  expectMasksCurrent(loaded, "load");
  std::string first;
  EXPECT_EQ(blocksWithOtherMasks(map, loaded, &first), 0u) << first;
  EXPECT_EQ(blocksWithOtherMasks(loaded, map, &first), 0u) << first;

  // After a reset the arena's slots are reused: no mask of the old map may survive.
  map.reset();
  EXPECT_EQ(map.blockCount(), 0u);
  map.insert(room(), poseAt(5), lidar());
  expectMasksCurrent(map, "reset and a scan");
}

}  // namespace
}  // namespace fragg::test
