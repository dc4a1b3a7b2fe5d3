// Forgetting (MapParams::dynamic.decay_log_odds_per_scan): bad rates refused, and with what it
// cannot be combined; over a sequence where a wall is seen and then never again, every scan
// equals a brute-force reference (the same scans into a map without decay, each followed by
// every observed cell moved one step toward log-odds 0 through a cell writer), state masks
// included; the wall fades to the unknown band with decay and stays occupied without it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "dynamic_scene.h"
#include "fragg_map/cell_writer.h"
#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "same_map.h"
#include "state_masks_check.h"

namespace fragg {
namespace {

using test::dynamicSceneCell;
using test::dynamicScenePose;

MapParams decayParams(double rate) {
  MapParams p = test::dynamicSceneParams(false, VoidSpaceRule::kPassThrough, 2);
  p.dynamic.decay_log_odds_per_scan = rate;
  return p;
}

/// A wall of cells at x = `x` (y, z in [-6, 6]) in front of (x > 0) or behind the sensor.
PointCloud wallCloud(int x) {
  PointCloud c;
  for (int y = -6; y <= 6; ++y)
    for (int z = -6; z <= 6; ++z) c.points_S.push_back(dynamicSceneCell(x, y, z));
  return c;
}

TEST(DecayTest, BadRatesAreRefused) {
  auto refused = [](auto edit) {
    MapParams p = decayParams(0.2);
    edit(p);
    EXPECT_THROW(Map{p}, InvalidArgument);
  };
  refused([](MapParams& p) { p.dynamic.decay_log_odds_per_scan = -0.1; });
  refused([](MapParams& p) { p.dynamic.decay_log_odds_per_scan = 4.01; });
  refused([](MapParams& p) { p.dynamic.decay_log_odds_per_scan = std::nan(""); });
  refused([](MapParams& p) {
    p.dynamic.decay_log_odds_per_scan = std::numeric_limits<double>::infinity();
  });
  refused([](MapParams& p) { p.scans.keep = true; });         // removal would not be exact
  refused([](MapParams& p) { p.backend = Backend::kCuda; });  // a pass over the host map
  MapParams auto_backend = decayParams(0.2);
  auto_backend.backend = Backend::kAuto;
  EXPECT_STREQ(Map(auto_backend).backendName(), "cpu");
  MapParams off = decayParams(0.0);  // off: the default, combined with anything
  off.scans.keep = true;
  EXPECT_NO_THROW(Map{off});
}

/// Every observed cell of `map` one step of `step_fx` toward 0, through a cell writer.
void bruteForceDecay(Map& map, int16_t step_fx) {
  std::vector<std::pair<VoxelKey, Cell>> cells;
  map.forEachBlock([&](const BlockKey& bk, const Block& block) {
    for (int ci = 0; ci < kCellsPerBlock; ++ci) {
      Cell c = block.cells[ci];
      if (!c.observed()) continue;
      const int v = c.log_odds_fx;
      c.log_odds_fx =
          static_cast<int16_t>(v > 0 ? std::max(0, v - step_fx) : std::min(0, v + step_fx));
      cells.push_back({voxelKeyOf(bk, ci), c});
    }
  });
  map.writeCells([&](CellWriter& w) {
    for (const auto& [key, cell] : cells) w.set(key, cell);
  });
}

TEST(DecayTest, WallSeenOnceFadesAsTheBruteForceReferenceDoes) {
  const double rate = 0.25;
  const int16_t step_fx = static_cast<int16_t>(std::lround(rate * kLogOddsScale));
  Map map(decayParams(rate)), ref(decayParams(0.0)), kept(decayParams(0.0));
  const SensorModel sensor = SensorModel::autoFromCloud();
  const VoxelKey front_wall{30, 0, 0};  // the sensor's voxel is (0, 0, 0)
  for (int scan = 0; scan < 24; ++scan) {
    // Three scans of the wall in front, then only the one behind.
    const PointCloud cloud = wallCloud(scan < 3 ? 30 : -30);
    map.insert(cloud, dynamicScenePose(), sensor);
    ref.insert(cloud, dynamicScenePose(), sensor);
    kept.insert(cloud, dynamicScenePose(), sensor);
    bruteForceDecay(ref, step_fx);
    test::expectSameMap(map, ref, "decayed map vs reference");
    EXPECT_EQ(test::blocksWithStaleMasks(map), 0u) << "scan " << scan;
    if (scan == 2) {
      ASSERT_NE(map.findCell(front_wall), nullptr);
      EXPECT_EQ(map.state(*map.findCell(front_wall)), CellState::kOccupied);
    }
  }
  // Not seen for 21 scans: faded to log-odds 0 with decay, still occupied without it.
  ASSERT_NE(map.findCell(front_wall), nullptr);
  EXPECT_EQ(map.findCell(front_wall)->log_odds_fx, 0);
  EXPECT_NE(map.state(*map.findCell(front_wall)), CellState::kOccupied);
  EXPECT_EQ(kept.state(*kept.findCell(front_wall)), CellState::kOccupied);
  // The wall behind, seen every scan, stays occupied with decay too.
  const VoxelKey back_wall{-30, 0, 0};
  EXPECT_EQ(map.state(*map.findCell(back_wall)), CellState::kOccupied);
}

}  // namespace
}  // namespace fragg
