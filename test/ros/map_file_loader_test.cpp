// The server's map files (~load_map, map_file): .fgm and .bt read into a map with the server's
// settings, the same cells as the saved map; another resolution, an unknown extension and a
// missing file refused; the map's copy for a .bt save written as the map.
#include "../../src/ros/server/map_file_loader.h"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <string>

#include "../../src/ros/server/map_copy.h"
#include "fragg_map/errors.h"
#include "fragg_map/interop/octomap_io.h"
#include "map_fixtures.h"

namespace {

using fragg::ros::loadMapFile;

std::string tmpPath(const std::string& name) { return std::string(FRAGG_TEST_TMP) + "/" + name; }

std::string fileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Every observed cell's state, by voxel key.
void expectSameStates(const fragg::Map& a, const fragg::Map& b) {
  size_t cells = 0;
  a.forEachBlock([&](const fragg::BlockKey& key, const fragg::Block& block) {
    for (int c = 0; c < fragg::kCellsPerBlock; ++c) {
      if (!block.cells[c].observed()) continue;
      const fragg::VoxelKey v = fragg::voxelKeyOf(key, c);
      const fragg::Cell* other = b.findCell(v);
      ASSERT_NE(other, nullptr);
      EXPECT_EQ(b.state(*other), a.state(block.cells[c]));
      ++cells;
    }
  });
  EXPECT_GT(cells, 100u);
  EXPECT_EQ(a.knownVoxelCount(), b.knownVoxelCount());
}

fragg::MapParams serverParams() {
  fragg::MapParams p = fragg::ros::test::cpuParams(0.1);
  p.scans.keep = true;
  return p;
}

TEST(MapFileLoader, FgmAndBtGiveTheSavedCellsWithTheServersSettings) {
  fragg::Map map(serverParams());
  fragg::ros::test::insertWall(map, Eigen::Vector3d(0.0, 0.0, 0.5), 2.0);
  map.save(tmpPath("loader.fgm"));
  fragg::exportOctomap(map, tmpPath("loader.bt"));

  const fragg::Map fgm = loadMapFile(tmpPath("loader.fgm"), serverParams());
  expectSameStates(map, fgm);
  EXPECT_EQ(fgm.scanCount(), 1u);
  EXPECT_EQ(fgm.scanStore().size(), 1u);

  const fragg::Map bt = loadMapFile(tmpPath("loader.bt"), serverParams());
  expectSameStates(map, bt);
  EXPECT_TRUE(bt.params().scans.keep);  // the server's settings, not the import's defaults
  EXPECT_EQ(bt.params().threads, 1);
  EXPECT_EQ(bt.scanCount(), 0u);
}

// The copy a .bt save and the GetOctomap services read without the map's lock (map_copy.h):
// every observed cell (negative keys included), so the .bt written from it is byte for byte
// the map's; an empty map gives an empty copy.
TEST(MapFileLoader, ObservedCopyWritesTheMapsBt) {
  fragg::Map map(serverParams());
  fragg::ros::test::insertWall(map, Eigen::Vector3d(0.0, 0.0, 0.5), 2.0);
  fragg::ros::test::insertWall(map, Eigen::Vector3d(-3.3, -1.7, -0.4), 1.5);
  const fragg::Map copy = fragg::ros::observedCopy(map);
  expectSameStates(map, copy);
  EXPECT_EQ(copy.resolution(), map.resolution());
  fragg::exportOctomap(map, tmpPath("copy_map.bt"));
  fragg::exportOctomap(copy, tmpPath("copy_copy.bt"));
  const std::string original = fileBytes(tmpPath("copy_map.bt"));
  EXPECT_GT(original.size(), 100u);
  EXPECT_EQ(fileBytes(tmpPath("copy_copy.bt")), original);
  const fragg::Map empty(serverParams());
  EXPECT_EQ(fragg::ros::observedCopy(empty).knownVoxelCount(), 0u);
}

TEST(MapFileLoader, RefusesAnotherResolutionExtensionOrMissingFile) {
  fragg::Map map(serverParams());
  fragg::ros::test::insertWall(map, Eigen::Vector3d(0.0, 0.0, 0.5), 2.0);
  map.save(tmpPath("loader_res.fgm"));
  fragg::exportOctomap(map, tmpPath("loader_res.bt"));
  fragg::MapParams other = serverParams();
  other.resolution_m = 0.05;
  EXPECT_THROW(loadMapFile(tmpPath("loader_res.fgm"), other), fragg::InvalidArgument);
  EXPECT_THROW(loadMapFile(tmpPath("loader_res.bt"), other), fragg::InvalidArgument);
  EXPECT_THROW(loadMapFile(tmpPath("loader_res.xyz"), serverParams()), fragg::InvalidArgument);
  EXPECT_THROW(loadMapFile(tmpPath("missing.bt"), serverParams()), fragg::IoError);
  EXPECT_THROW(loadMapFile(tmpPath("missing.fgm"), serverParams()), fragg::IoError);
}

}  // namespace
