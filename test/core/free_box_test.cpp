// Map::freeBox, octomap_server's clear_bbx rule: the observed cells whose keys lie in the box
// become free at the lower clamp (hit counts kept), unknown cells stay unknown, nothing outside
// the box changes, and a bad box changes nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/map.h"

namespace fragg {
namespace {

MapParams cpuParams() {
  MapParams p;
  p.resolution_m = 0.1;
  p.backend = Backend::kCpu;
  p.threads = 1;
  return p;
}

struct Sample {
  VoxelKey key;
  int16_t log_odds_fx;
  int16_t hits;
};

// Cells in every state, inside the box of keys [0, 9] (0.0 .. 0.99 m at 10 cm) and outside it,
// across several blocks.
std::vector<Sample> samples(const OccupancyModel& m) {
  return {
      {{0, 0, 0}, m.max_fx, 7},    {{9, 9, 9}, 1200, 2},     {{5, 2, 7}, 40, 0},  // in: occupied,
      {{3, 8, 1}, -300, 0},        {{8, 0, 4}, m.min_fx, 0},                      // band, free
      {{-1, 0, 0}, m.max_fx, 3},   {{10, 5, 5}, 900, 1},     {{4, 4, 10}, -500, 0},  // out
      {{12, 12, 12}, m.max_fx, 1},
  };
}

bool inBox(const VoxelKey& k) {
  auto in = [](int32_t v) { return v >= 0 && v <= 9; };
  return in(k.x) && in(k.y) && in(k.z);
}

Map sampleMap() {
  Map map(cpuParams());
  const std::vector<Sample> cells = samples(map.model());
  map.writeCells([&](CellWriter& w) {
    for (const Sample& s : cells) {
      Cell c;
      c.log_odds_fx = s.log_odds_fx;
      c.hits = s.hits;
      w.set(s.key, c);
    }
  });
  return map;
}

TEST(FreeBox, KnownCellsInTheBoxBecomeFreeAtTheLowerClampOthersUnchanged) {
  Map map = sampleMap();
  const std::vector<Sample> cells = samples(map.model());
  const uint64_t known = map.knownVoxelCount();
  const uint64_t revision = map.revision();
  // Box corners inside the cells of keys 0 and 9 (keys of the corners, inclusive).
  const uint64_t set = map.freeBox({0.05, 0.01, 0.0}, {0.95, 0.99, 0.91});
  EXPECT_EQ(set, 5u);
  EXPECT_EQ(map.knownVoxelCount(), known);  // free, not unknown
  EXPECT_GT(map.revision(), revision);
  for (const Sample& s : cells) {
    SCOPED_TRACE(testing::Message() << s.key.x << " " << s.key.y << " " << s.key.z);
    const Cell* c = map.findCell(s.key);
    ASSERT_NE(c, nullptr);
    EXPECT_EQ(c->hits, s.hits);
    if (inBox(s.key)) {
      EXPECT_EQ(c->log_odds_fx, map.model().min_fx);
      EXPECT_EQ(map.state(*c), CellState::kFree);
    } else {
      EXPECT_EQ(c->log_odds_fx, s.log_odds_fx);
    }
  }
  // Unknown cells in the box stay unknown (no block, or an unobserved cell of a block).
  const Cell* unknown = map.findCell({1, 1, 1});
  EXPECT_TRUE(unknown == nullptr || !unknown->observed());
  // Readers of changed blocks see the block of the occupied cell at the origin.
  const std::vector<BlockKey> changed = map.changedBlocksSince(revision);
  EXPECT_NE(std::find(changed.begin(), changed.end(), blockKeyOf(VoxelKey{0, 0, 0})),
            changed.end());
}

TEST(FreeBox, BadBoxesAreRefusedAndChangeNothing) {
  Map map = sampleMap();
  const uint64_t revision = map.revision();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(map.freeBox({1, 1, 1}, {0, 0, 0}), InvalidArgument);
  EXPECT_THROW(map.freeBox({nan, 0, 0}, {1, 1, 1}), InvalidArgument);
  EXPECT_EQ(map.revision(), revision);
  EXPECT_EQ(map.findCell({0, 0, 0})->log_odds_fx, map.model().max_fx);
}

TEST(FreeBox, AFreedBoxIsWhatRaysThroughItWouldLeaveAtTheClamp) {
  // After freeBox, a later insertion treats the cells like any free cell at the clamp: a hit
  // moves the cell up from min_fx exactly as it moves a cell made free by writeCells.
  Map freed = sampleMap();
  freed.freeBox({0, 0, 0}, {0.99, 0.99, 0.99});
  Map written = sampleMap();
  written.writeCells([&](CellWriter& w) {
    for (const Sample& s : samples(written.model())) {
      if (!inBox(s.key)) continue;
      Cell c;
      c.log_odds_fx = written.model().min_fx;
      c.hits = s.hits;
      w.set(s.key, c);
    }
  });
  PointCloud cloud;  // in the sensor frame: rays from a cell centre through the freed box
  cloud.points_S = {Eigen::Vector3f(0.2f, -0.2f, 0.5f), Eigen::Vector3f(-0.3f, -0.4f, -0.2f),
                    Eigen::Vector3f(0.5f, 0.5f, 0.5f)};
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(0.35, 0.45, 0.25);
  freed.insert(cloud, pose, SensorModel::autoFromCloud());
  written.insert(cloud, pose, SensorModel::autoFromCloud());
  ASSERT_EQ(freed.knownVoxelCount(), written.knownVoxelCount());
  freed.forEachBlock([&](const BlockKey& key, const Block& block) {
    const Block* other = written.findBlock(key);
    ASSERT_NE(other, nullptr);
    for (int i = 0; i < kCellsPerBlock; ++i)
      EXPECT_EQ(block.cells[i].log_odds_fx, other->cells[i].log_odds_fx) << i;
  });
}

}  // namespace
}  // namespace fragg
