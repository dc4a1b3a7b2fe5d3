// Full OctoMap trees (.ot, octomap_full's data): pruned as octomap_server's compress_map
// prunes them, losslessly, and smaller than one leaf per cell.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <memory>
#include <sstream>
#include <string>

#include "fragg_map/interop/octomap_io.h"
#include "interop_test_util.h"

namespace fragg {
namespace {

using test::cellFx;
using test::paramsAt;
using test::readBytes;
using test::testDir;

// A 16 x 16 x 16 cube of saturated free cells (what a cleared room holds: OctoMap prunes it to
// one leaf of 16 cells' edge), a wall of occupied cells at x = 16 with one cell of another
// value in it, and a few scattered cells with distinct values.
Map sampleMap() {
  Map map(paramsAt(0.1));
  const OccupancyModel& m = map.model();
  map.writeCells([&](CellWriter& cells) {
    Cell c;
    for (int z = 0; z < 16; ++z)
      for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) {
          c.log_odds_fx = m.min_fx;
          cells.set({x, y, z}, c);
        }
    for (int z = 0; z < 8; ++z)
      for (int y = 0; y < 8; ++y) {
        c.log_odds_fx = (y == 3 && z == 5) ? 1500 : m.max_fx;
        cells.set({16, y, z}, c);
      }
    c.log_odds_fx = -123;
    cells.set({-5, 7, 2}, c);
    c.log_odds_fx = 456;
    cells.set({40, -3, -9}, c);
  });
  return map;
}

size_t leavesOf(const std::string& data, double resolution) {
  octomap::OcTree tree(resolution);
  std::istringstream in(data);
  tree.readData(in);
  return tree.getNumLeafNodes();
}

void expectSameCells(const Map& a, const Map& b) {
  ASSERT_EQ(a.knownVoxelCount(), b.knownVoxelCount());
  uint64_t checked = 0;
  a.forEachBlock([&](const BlockKey& key, const Block& block) {
    for (int i = 0; i < kCellsPerBlock; ++i) {
      if (!block.cells[i].observed()) continue;
      const VoxelKey v = voxelKeyOf(key, i);
      EXPECT_EQ(cellFx(b, v), block.cells[i].log_odds_fx) << v.x << " " << v.y << " " << v.z;
      ++checked;
    }
  });
  EXPECT_EQ(checked, a.knownVoxelCount());
}

TEST(OctomapFull, PrunedDataMergesEqualLeavesAndLosesNothing) {
  const Map map = sampleMap();
  const uint64_t cells = map.knownVoxelCount();
  ASSERT_EQ(cells, 16u * 16 * 16 + 64 + 2);
  const std::string full = octomapFullData(map, /*prune=*/false);
  const std::string pruned = octomapFullData(map, /*prune=*/true);
  EXPECT_EQ(leavesOf(full, 0.1), cells);  // one leaf a cell
  // The free cube is one leaf; the wall's 8 x 8 face is 8 x 8 x 1 cells, one row of 2 x 2 x 2
  // nodes is impossible (1 cell thick), so it stays 64 leaves; 2 scattered leaves.
  EXPECT_EQ(leavesOf(pruned, 0.1), 1u + 64 + 2);
  EXPECT_LT(pruned.size() * 10, full.size());
}

TEST(OctomapFull, OtFilesReadBackToTheSameCellsPrunedOrNot) {
  const Map map = sampleMap();
  const std::string dir = testDir();
  exportOctomapFull(map, dir + "/pruned.ot", /*prune=*/true);
  exportOctomapFull(map, dir + "/full.ot", /*prune=*/false);
  const std::string pruned_bytes = readBytes(dir + "/pruned.ot");
  EXPECT_EQ(pruned_bytes.rfind("# Octomap OcTree file\n", 0), 0u);
  EXPECT_LT(pruned_bytes.size(), readBytes(dir + "/full.ot").size());
  expectSameCells(map, importOctomap(dir + "/pruned.ot", Backend::kCpu));
  expectSameCells(map, importOctomap(dir + "/full.ot", Backend::kCpu));
}

}  // namespace
}  // namespace fragg
