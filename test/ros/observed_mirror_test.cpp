// The frontier topics' mirror of the observed cells (observed_mirror.h): after every refresh
// its cells equal the map's, cell for cell, through insertions, direct cell writes, freeBox,
// clearBox (blocks erased: a rebuild) and reset; only changed blocks are listed between
// refreshes, and the pieces are copied under as many read locks as the piece size makes.
#include "../../src/ros/server/observed_mirror.h"

#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <tuple>

#include "fragg_map/errors.h"
#include "map_fixtures.h"

namespace {

using fragg::ros::ObservedMirror;
using fragg::ros::SharedMap;
using fragg::ros::test::cpuParams;
using fragg::ros::test::insertWall;

struct KeyLess {
  bool operator()(const fragg::VoxelKey& a, const fragg::VoxelKey& b) const {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  }
};

// Every observed cell (log-odds and hit count), by voxel key.
std::map<fragg::VoxelKey, std::pair<int16_t, int16_t>, KeyLess> observedCells(
    const fragg::Map& map) {
  std::map<fragg::VoxelKey, std::pair<int16_t, int16_t>, KeyLess> out;
  map.forEachBlock([&](const fragg::BlockKey& key, const fragg::Block& block) {
    for (int c = 0; c < fragg::kCellsPerBlock; ++c)
      if (block.cells[c].observed())
        out[fragg::voxelKeyOf(key, c)] = {block.cells[c].log_odds_fx, block.cells[c].hits};
  });
  return out;
}

void expectMirrors(const SharedMap& shared, const ObservedMirror& mirror) {
  const auto state = shared.read();
  const auto want = observedCells(state->map);
  const auto got = observedCells(mirror.map());
  EXPECT_EQ(got.size(), want.size());
  EXPECT_TRUE(got == want);
  EXPECT_EQ(mirror.revision(), state->map.revision());
  EXPECT_EQ(mirror.map().resolution(), state->map.resolution());
  EXPECT_EQ(mirror.map().knownVoxelCount(), state->map.knownVoxelCount());
}

TEST(ObservedMirror, FollowsTheMapThroughEditsInPieces) {
  SharedMap shared(fragg::ros::MapState(fragg::Map(cpuParams(0.1))));
  ObservedMirror mirror(/*blocks_per_lock=*/3);
  EXPECT_EQ(mirror.map().knownVoxelCount(), 0u);

  // An empty map: one lock, nothing listed.
  ObservedMirror::RefreshStats s = mirror.refresh(shared);
  EXPECT_TRUE(s.rebuilt);
  EXPECT_EQ(s.blocks_listed, 0u);
  EXPECT_EQ(s.locks, 1u);
  expectMirrors(shared, mirror);

  insertWall(shared.write()->map, Eigen::Vector3d(0.0, 0.0, 0.5), 2.0);
  s = mirror.refresh(shared);
  EXPECT_FALSE(s.rebuilt);  // nothing erased since the first refresh
  const size_t blocks = shared.read()->map.blockCount();
  EXPECT_EQ(s.blocks_listed, blocks);
  EXPECT_EQ(s.locks, 1 + (blocks + 2) / 3);
  EXPECT_TRUE(s.complete);
  expectMirrors(shared, mirror);

  // Unchanged: nothing listed, one lock.
  s = mirror.refresh(shared);
  EXPECT_EQ(s.blocks_listed, 0u);
  EXPECT_EQ(s.locks, 1u);

  // A second wall elsewhere: only its blocks (and those the rays crossed) are listed.
  insertWall(shared.write()->map, Eigen::Vector3d(5.0, 4.0, 0.5), 1.5);
  s = mirror.refresh(shared);
  EXPECT_FALSE(s.rebuilt);
  EXPECT_GT(s.blocks_listed, 0u);
  EXPECT_LT(s.blocks_listed, shared.read()->map.blockCount());
  expectMirrors(shared, mirror);

  // A cell made unknown and one made occupied by direct writes; freeBox sets observed cells.
  {
    auto state = shared.write();
    fragg::ros::test::setCell(state->map, fragg::VoxelKey{20, 0, 5}, fragg::CellState::kUnknown);
    fragg::ros::test::setCell(state->map, fragg::VoxelKey{-7, 3, 2}, fragg::CellState::kOccupied);
    state->map.freeBox(Eigen::Vector3d(1.0, -0.5, 0.0), Eigen::Vector3d(1.6, 0.5, 1.0));
  }
  s = mirror.refresh(shared);
  EXPECT_FALSE(s.rebuilt);
  expectMirrors(shared, mirror);

  // clearBox erases blocks (a new view epoch): the mirror is rebuilt without them.
  shared.write()->map.clearBox(Eigen::Vector3d(-1.0, -2.0, -1.0), Eigen::Vector3d(3.0, 2.0, 2.0));
  s = mirror.refresh(shared);
  EXPECT_TRUE(s.rebuilt);
  expectMirrors(shared, mirror);

  // Cleared (the markers' subscriber left): empty until the next refresh rebuilds it.
  mirror.clear();
  EXPECT_EQ(mirror.map().knownVoxelCount(), 0u);
  EXPECT_TRUE(mirror.refresh(shared).rebuilt);
  expectMirrors(shared, mirror);

  shared.write()->map.reset();
  s = mirror.refresh(shared);
  EXPECT_TRUE(s.rebuilt);
  expectMirrors(shared, mirror);
  EXPECT_EQ(mirror.map().knownVoxelCount(), 0u);
}

// A map loaded in place (~load_map) with another resolution: the copy follows it.
TEST(ObservedMirror, FollowsAMapReplacedWithAnotherResolution) {
  SharedMap shared(fragg::ros::MapState(fragg::Map(cpuParams(0.1))));
  insertWall(shared.write()->map, Eigen::Vector3d(0.0, 0.0, 0.5), 2.0);
  ObservedMirror mirror;
  (void)mirror.refresh(shared);
  expectMirrors(shared, mirror);
  {
    auto state = shared.write();
    state->map = fragg::Map(cpuParams(0.2));
    insertWall(state->map, Eigen::Vector3d(1.0, 1.0, 0.5), 2.5);
  }
  EXPECT_TRUE(mirror.refresh(shared).rebuilt);
  expectMirrors(shared, mirror);
}

TEST(ObservedMirror, RefusesEmptyPieces) {
  EXPECT_THROW(ObservedMirror(0), fragg::InvalidArgument);
}

// CellWriter::setBlock, which the mirror copies with: the cells that differ are written, a
// block with no observed cell is not made, negative hit counts are refused with nothing written.
TEST(ObservedMirror, SetBlockWritesWhatDiffers) {
  fragg::Map source(cpuParams(0.1)), copy(cpuParams(0.1));
  insertWall(source, Eigen::Vector3d(0.0, 0.0, 0.5), 2.0);
  copy.writeCells([&](fragg::CellWriter& w) {
    source.forEachBlock([&](const fragg::BlockKey& k, const fragg::Block& b) { w.setBlock(k, b); });
    EXPECT_EQ(w.cellsWritten(), source.knownVoxelCount());  // only observed cells differ
  });
  EXPECT_TRUE(observedCells(copy) == observedCells(source));
  for (const fragg::BlockKey& k : {fragg::BlockKey{0, 0, 0}, fragg::BlockKey{1, 0, 0}}) {
    if (const fragg::Block* b = source.findBlock(k)) {
      const fragg::BlockStateMasks* want = source.findMasks(k);
      const fragg::BlockStateMasks* got = copy.findMasks(k);
      ASSERT_NE(got, nullptr);
      EXPECT_EQ(0, std::memcmp(got, want, sizeof(*got)));
      (void)b;
    }
  }
  const size_t before = copy.blockCount();
  copy.writeCells([&](fragg::CellWriter& w) {
    w.setBlock(fragg::BlockKey{100, 100, 100}, fragg::Block());  // nothing observed: not made
    EXPECT_EQ(w.cellsWritten(), 0u);
    fragg::Block bad;
    bad.cells[7].hits = -1;
    bad.cells[7].log_odds_fx = 100;
    EXPECT_THROW(w.setBlock(fragg::BlockKey{101, 100, 100}, bad), fragg::InvalidArgument);
  });
  EXPECT_EQ(copy.blockCount(), before);
}

}  // namespace
