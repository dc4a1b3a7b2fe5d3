// The cell states the CPU update keeps per block (BlockMap::knownStates, block_states.h):
// wherever a reader is handed them they must equal the states of the block's cells, through
// inserts, removals, pose corrections and every other writer (which must end them, not leave
// them stale); and the update keeps them for the blocks it touches.
#include "fragg_map/block_states.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <string>

#include "fragg_map/map.h"
#include "test_scenes.h"

namespace fragg {
namespace {

MapParams params() {
  MapParams p;
  p.resolution_m = 0.05;
  p.backend = Backend::kCpu;  // the update that keeps them (the CUDA backend keeps none)
  p.scans.keep = true;        // removal and correction need the scans
  return p;
}

Eigen::Isometry3d poseAt(int i) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.017 * i - 0.2, 0.023 * (i % 5) - 0.05, 1.2 + 0.004 * i);
  T.rotate(Eigen::AngleAxisd(0.07 * i, Eigen::Vector3d::UnitZ()));
  return T;
}

struct Census {
  size_t blocks = 0, known = 0, wrong = 0;
};

/// Every block: its kept states, where it has them, against the states of its cells.
Census census(const Map& map) {
  Census c;
  for (const BlockRef& ref : map.blockView().all()) {
    ++c.blocks;
    if (!ref.states) continue;
    ++c.known;
    if (*ref.states != blockStatesOf(*ref.block, map.model())) ++c.wrong;
  }
  return c;
}

void expectAllKnownAndRight(const Map& map, const std::string& what) {
  const Census c = census(map);
  EXPECT_GT(c.blocks, 0u) << what;
  EXPECT_EQ(c.known, c.blocks) << what;
  EXPECT_EQ(c.wrong, 0u) << what;
}

void expectNoneWrong(const Map& map, const std::string& what) {
  EXPECT_EQ(census(map).wrong, 0u) << what;
}

TEST(BlockStates, MasksAreTheModelsStatesOfEachCell) {
  Map map(params());
  const OccupancyModel& model = map.model();
  Block block;
  // Every state, at thresholds and clamps, spread over all eight layers.
  const int16_t values[] = {kUnobservedLogOdds,
                            model.min_fx,
                            model.free_below_fx,
                            static_cast<int16_t>(model.free_below_fx - 1),
                            0,
                            model.occupied_above_fx,
                            static_cast<int16_t>(model.occupied_above_fx + 1),
                            model.max_fx};
  constexpr int kValues = sizeof(values) / sizeof(values[0]);
  for (int c = 0; c < kCellsPerBlock; ++c)
    block.cells[c].log_odds_fx = values[(c * 7 + c / 64) % kValues];
  const BlockStates s = blockStatesOf(block, model);
  for (int c = 0; c < kCellsPerBlock; ++c) {
    const Cell& cell = block.cells[c];
    const int z = c / 64, bit = c % 64;
    const CellState state = model.state(cell);
    EXPECT_EQ((s.occupied[z] >> bit) & 1, state == CellState::kOccupied ? 1u : 0u) << c;
    EXPECT_EQ((s.free[z] >> bit) & 1, state == CellState::kFree ? 1u : 0u) << c;
    EXPECT_EQ((s.observed[z] >> bit) & 1, cell.observed() ? 1u : 0u) << c;
  }
}

TEST(BlockStates, TheUpdateKeepsThemThroughInsertsRemovalsAndCorrections) {
  const PointCloud room = test::roomScan(3.0, 1.2, 1.5, 32, 360);
  Map map(params());
  std::vector<ScanId> ids;
  for (int i = 0; i < 10; ++i) {
    ids.push_back(map.insert(room, poseAt(i), SensorModel::autoFromCloud()).scan_id);
    expectAllKnownAndRight(map, "insert " + std::to_string(i));
  }
  map.remove(ids[2]);
  expectAllKnownAndRight(map, "after a removal");
  std::map<ScanId, Eigen::Isometry3d> moved;
  moved[ids[4]] = poseAt(20);
  moved[ids[7]] = poseAt(21);
  map.correctPoses(moved);
  expectAllKnownAndRight(map, "after a pose correction");
}

TEST(BlockStates, OtherWritersEndThemAndTheNextUpdateRestoresThem) {
  const PointCloud room = test::roomScan(3.0, 1.2, 1.5, 32, 360);
  Map map(params());
  for (int i = 0; i < 6; ++i) map.insert(room, poseAt(i), SensorModel::autoFromCloud());
  expectAllKnownAndRight(map, "inserts");

  // A single cell turned occupied in a block whose states were known: the block must no
  // longer hand out the old ones.
  const VoxelKey edited = map.keyOf(Eigen::Vector3d(0.01, 0.02, 1.3));
  ASSERT_NE(map.findBlock(blockKeyOf(edited)), nullptr);
  ASSERT_NE(map.blockView().findRef(blockKeyOf(edited)).states, nullptr);
  map.writeCells([&](CellWriter& w) {
    Cell c;
    c.log_odds_fx = map.model().max_fx;
    w.set(edited, c);
  });
  EXPECT_EQ(map.blockView().findRef(blockKeyOf(edited)).states, nullptr);
  expectNoneWrong(map, "after a cell write");

  map.clearBox(Eigen::Vector3d(-1.0, -1.0, 0.5), Eigen::Vector3d(1.0, 1.0, 2.0));
  expectNoneWrong(map, "after clearing a box");

  const Map sub = map.extract(Eigen::Vector3d(-2.0, -2.0, 0.0), Eigen::Vector3d(2.0, 2.0, 2.5));
  expectNoneWrong(sub, "an extracted sub-map");
  map.merge(sub, MergeMode::kAdd);
  expectNoneWrong(map, "after a merge");

  const std::string path = ::testing::TempDir() + "block_states_test.fgm";
  map.save(path);
  const Map loaded = Map::load(path);
  expectNoneWrong(loaded, "a loaded map");

  // Scans seeing the whole room again: every block the rays reach is known again.
  for (int i = 6; i < 10; ++i) map.insert(room, poseAt(i), SensorModel::autoFromCloud());
  const Census c = census(map);
  EXPECT_EQ(c.wrong, 0u);
  EXPECT_GT(c.known, c.blocks * 9 / 10) << c.known << " of " << c.blocks;
  std::remove(path.c_str());
}

}  // namespace
}  // namespace fragg
