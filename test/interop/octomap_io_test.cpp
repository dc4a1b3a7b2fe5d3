// OctoMap interop: .bt export against liboctomap, round trips, key range, corrupt files.
#include "fragg_map/interop/octomap_io.h"

#include <gtest/gtest.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <sstream>
#include <utility>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/interop/compare.h"
#include "interop_test_util.h"

namespace fragg {
namespace {

using test::cellFx;
using test::fileExists;
using test::listDir;
using test::paramsAt;
using test::readBytes;
using test::setCell;
using test::stateAt;
using test::testDir;
using test::writeBytes;

using CellList = std::vector<std::pair<VoxelKey, int16_t>>;

Map mapOf(const MapParams& params, const CellList& cells) {
  Map map(params);
  for (const auto& [k, fx] : cells) setCell(map, k, fx);
  return map;
}

/// Cells of every kind: clamped, unclamped, in the unknown band, exactly 0, negative keys,
/// the extremes of OctoMap's key range, and a full free block that OctoMap prunes.
CellList mixedCells(const OccupancyModel& m) {
  CellList cells = {
      {{0, 0, 0}, m.max_fx},
      {{1, 0, 0}, m.min_fx},
      {{-1, -2, -3}, 2000},
      {{-9, 5, 17}, -700},
      {{3, 3, 3}, 100},  // p = 0.525: inside the unknown band, but occupied for OctoMap
      {{4, 3, 3}, 0},    // p = 0.5: OctoMap's isNodeOccupied says occupied
      {{5, 3, 3}, -1},
      {{kOctomapMaxKey, 0, 0}, m.max_fx},
      {{kOctomapMinKey, kOctomapMinKey, kOctomapMaxKey}, m.min_fx},
  };
  for (int z = 16; z < 24; ++z)
    for (int y = 16; y < 24; ++y)
      for (int x = 16; x < 24; ++x) cells.push_back({{x, y, z}, -900});
  return cells;
}

TEST(OctomapIo, BtRoundTripKeepsEveryCellAndItsState) {
  const std::string path = testDir() + "/map.bt";
  const Map map = mapOf(paramsAt(0.05), mixedCells(Map(paramsAt(0.05)).model()));
  exportOctomap(map, path);
  const Map back = importOctomap(path);

  EXPECT_DOUBLE_EQ(back.resolution(), 0.05);
  // A .bt holds occupied/free bits only: the reader puts leaves at its clamping thresholds.
  const OccupancyParams& occ = back.params().occupancy;
  EXPECT_NEAR(occ.clamp_max, 0.971, 1e-4);
  EXPECT_NEAR(occ.clamp_min, 0.1192, 1e-4);
  EXPECT_EQ(back.knownVoxelCount(), map.knownVoxelCount());
  for (const auto& [k, fx] : mixedCells(map.model())) {
    SCOPED_TRACE(testing::Message() << "cell " << k.x << " " << k.y << " " << k.z);
    const bool occupied = fx >= 0;
    EXPECT_EQ(stateAt(back, k), occupied ? CellState::kOccupied : CellState::kFree);
    EXPECT_NEAR(cellFx(back, k), logOddsFxOf(occupied ? occ.clamp_max : occ.clamp_min), 1);
    if (stateAt(map, k) != CellState::kUnknown) {  // outside the band: the same state
      EXPECT_EQ(stateAt(back, k), stateAt(map, k));
    }
  }
}

TEST(OctomapIo, BtRoundTripKeepsLogOddsAtOctomapClamps) {
  MapParams params = paramsAt(0.1);
  params.occupancy.clamp_min = 0.1192;  // liboctomap's own defaults, which a .bt reader uses
  params.occupancy.clamp_max = 0.971;
  Map map(params);
  const CellList cells = {{{2, -3, 4}, map.model().max_fx}, {{-7, 0, 1}, map.model().min_fx}};
  for (const auto& [k, fx] : cells) setCell(map, k, fx);
  const std::string path = testDir() + "/clamped.bt";
  exportOctomap(map, path);
  const Map back = importOctomap(path);
  for (const auto& [k, fx] : cells) {
    // Float log-odds in the tree, rounded to 1/1024 on the way back.
    EXPECT_NEAR(cellFx(back, k) / 1024.0, fx / 1024.0, 1.0 / 1024 + 1e-6);
  }
}

TEST(OctomapIo, ExportMatchesOcTreeBuiltDirectly) {
  const std::string path = testDir() + "/direct.bt";
  Map map(paramsAt(0.1));
  const CellList cells = {{{0, 0, 0}, 1500},    {{1, 0, 0}, -400},  {{-5, -6, -7}, 3000},
                          {{30, -2, 9}, -2000}, {{-1, 0, 0}, 10},   {{7, 7, 7}, -1},
                          {{8, 8, 8}, 0},       {{12, -40, 3}, 900}};
  for (const auto& [k, fx] : cells) setCell(map, k, fx);

  // The same cells through liboctomap's own API, placed by coordinate (coordToKey).
  octomap::OcTree direct(0.1);
  direct.setProbHit(0.7);
  direct.setProbMiss(0.4);
  direct.setClampingThresMin(0.12);
  direct.setClampingThresMax(0.97);
  for (const auto& [k, fx] : cells) {
    const Eigen::Vector3d c = map.centerOf(k);
    ASSERT_NE(direct.setNodeValue(c.x(), c.y(), c.z(), fx / 1024.0f), nullptr);
  }

  const std::unique_ptr<octomap::OcTree> tree = toOcTree(map);
  EXPECT_DOUBLE_EQ(tree->getResolution(), 0.1);
  EXPECT_NEAR(tree->getProbHit(), 0.7, 1e-6);
  EXPECT_NEAR(tree->getProbMiss(), 0.4, 1e-6);
  EXPECT_NEAR(tree->getClampingThresMin(), 0.12, 1e-6);
  EXPECT_NEAR(tree->getClampingThresMax(), 0.97, 1e-6);
  EXPECT_NEAR(tree->getOccupancyThres(), 0.5, 1e-9);
  EXPECT_EQ(tree->getNumLeafNodes(), direct.getNumLeafNodes());
  size_t leaves = 0;
  for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it, ++leaves) {
    const octomap::OcTreeNode* d = direct.search(it.getKey());
    ASSERT_NE(d, nullptr);
    EXPECT_FLOAT_EQ(it->getLogOdds(), d->getLogOdds());
  }
  EXPECT_EQ(leaves, cells.size());

  exportOctomap(map, path);
  std::ostringstream expected(std::ios::out | std::ios::binary);
  ASSERT_TRUE(direct.writeBinary(expected));
  EXPECT_EQ(readBytes(path), expected.str());
}

TEST(OctomapIo, CellsOutsideOctomapKeyRangeAreRejected) {
  const std::string dir = testDir();
  for (const VoxelKey& bad : {VoxelKey{kOctomapMaxKey + 1, 0, 0},
                              VoxelKey{0, kOctomapMinKey - 1, 0}, VoxelKey{0, 0, 100000}}) {
    Map map(paramsAt(0.05));
    setCell(map, {1, 2, 3}, 500);
    setCell(map, bad, 500);
    EXPECT_THROW(toOcTree(map), IoError);
    try {
      exportOctomap(map, dir + "/far.bt");
      ADD_FAILURE() << "export of a cell at x=" << bad.x << " did not throw";
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find("16-bit key range"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(listDir(dir).empty()) << "left behind: " << listDir(dir).front();
  }
}

TEST(OctomapIo, OtRoundTripKeepsExactLogOdds) {
  const std::string path = testDir() + "/exact.ot";
  Map map(paramsAt(0.02));
  const CellList cells = {{{0, 0, 0}, 1},           {{1, 1, 1}, -1},     {{2, 2, 2}, 0},
                          {{-3, 4, -5}, 5000},      {{9, -9, 9}, -3000}, {{100, 200, -300}, 1234},
                          {{-64, -64, -64}, -32767}};
  for (const auto& [k, fx] : cells) setCell(map, k, fx);
  ASSERT_TRUE(toOcTree(map)->write(path));
  const Map back = importOctomap(path);
  EXPECT_DOUBLE_EQ(back.resolution(), 0.02);
  EXPECT_EQ(back.knownVoxelCount(), cells.size());
  for (const auto& [k, fx] : cells) EXPECT_EQ(cellFx(back, k), fx);
}

TEST(OctomapIo, ImportExpandsCoarseLeaves) {
  const std::string path = testDir() + "/coarse.bt";
  octomap::OcTree tree(0.2);
  // Two aligned 4^3 cubes (one on each side of the origin) that prune into depth-14 leaves.
  for (int z = 0; z < 4; ++z)
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 4; ++x) {
        tree.setNodeValue(octomap::OcTreeKey(32768 + x, 32768 + y, 32768 + z), -1.5f);
        tree.setNodeValue(octomap::OcTreeKey(32764 + x, 32764 + y, 32764 + z), 2.5f);
      }
  tree.prune();
  ASSERT_EQ(tree.getNumLeafNodes(), 2u);
  ASSERT_TRUE(tree.writeBinary(path));

  const Map back = importOctomap(path);
  EXPECT_EQ(back.knownVoxelCount(), 128u);
  for (int z = 0; z < 4; ++z)
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 4; ++x) {
        EXPECT_EQ(stateAt(back, {x, y, z}), CellState::kFree);
        EXPECT_EQ(stateAt(back, {x - 4, y - 4, z - 4}), CellState::kOccupied);
      }
  EXPECT_EQ(stateAt(back, {4, 0, 0}), CellState::kUnknown);
  EXPECT_EQ(stateAt(back, {-5, -1, -1}), CellState::kUnknown);
}

TEST(OctomapIo, EmptyMapRoundTrip) {
  const std::string path = testDir() + "/empty.bt";
  exportOctomap(Map(paramsAt(0.25)), path);
  const Map back = importOctomap(path);
  EXPECT_DOUBLE_EQ(back.resolution(), 0.25);
  EXPECT_EQ(back.knownVoxelCount(), 0u);
}

TEST(OctomapIo, FromOcTreeTakesTheTreeParameters) {
  octomap::OcTree tree(0.125);
  tree.setProbHit(0.8);
  tree.setProbMiss(0.3);
  tree.setClampingThresMin(0.2);
  tree.setClampingThresMax(0.9);
  tree.updateNode(octomap::point3d(0.3f, -0.3f, 1.0f), true);
  const Map map = fromOcTree(tree);
  EXPECT_DOUBLE_EQ(map.resolution(), 0.125);
  EXPECT_NEAR(map.params().occupancy.prob_hit, 0.8, 1e-6);
  EXPECT_NEAR(map.params().occupancy.prob_miss, 0.3, 1e-6);
  EXPECT_NEAR(map.params().occupancy.clamp_min, 0.2, 1e-6);
  EXPECT_NEAR(map.params().occupancy.clamp_max, 0.9, 1e-6);
  EXPECT_EQ(map.knownVoxelCount(), 1u);
  EXPECT_NEAR(cellFx(map, map.keyOf({0.3, -0.3, 1.0})), logOdds(0.8) * 1024, 1);
}

TEST(OctomapIo, ImportsColorOcTree) {
  const std::string path = testDir() + "/color.ot";
  octomap::ColorOcTree tree(0.1);
  tree.updateNode(octomap::point3d(0.05f, 0.05f, 0.05f), true);
  tree.setNodeColor(octomap::OcTreeKey(32768, 32768, 32768), 10, 20, 30);
  tree.updateNode(octomap::point3d(-0.05f, 0.05f, 0.05f), false);
  ASSERT_TRUE(tree.write(path));
  const Map map = importOctomap(path);
  EXPECT_EQ(map.knownVoxelCount(), 2u);
  EXPECT_NEAR(cellFx(map, {0, 0, 0}), logOdds(0.7) * 1024, 1);
  EXPECT_NEAR(cellFx(map, {-1, 0, 0}), logOdds(0.4) * 1024, 1);
}

TEST(OctomapIo, MapAgreesWithItsBtExportUnderOctomapThreshold) {
  const std::string path = testDir() + "/agree.bt";
  const Map map = mapOf(paramsAt(0.05), mixedCells(Map(paramsAt(0.05)).model()));
  exportOctomap(map, path);
  CompareOptions options;
  options.octomap_threshold = true;
  const MapComparison c = compareMaps(map, importOctomap(path), options);
  EXPECT_EQ(c.known_in_both, map.knownVoxelCount());
  EXPECT_EQ(c.known_in_either, map.knownVoxelCount());
  EXPECT_EQ(c.agreeing, map.knownVoxelCount());
}

void expectRejected(const std::string& path, const std::string& bytes, const char* what) {
  writeBytes(path, bytes);
  EXPECT_THROW(importOctomap(path), IoError) << what;
}

TEST(OctomapIo, MissingAndCorruptFilesAreRejected) {
  const std::string dir = testDir();
  EXPECT_THROW(importOctomap(dir + "/missing.bt"), IoError);
  EXPECT_THROW(importOctomap(dir), IoError);

  Map map(paramsAt(0.1));
  for (int i = 0; i < 40; ++i) setCell(map, {i % 7 - 3, i / 7, i % 3}, i % 2 ? 900 : -900);
  exportOctomap(map, dir + "/good.bt");
  const std::string good = readBytes(dir + "/good.bt");
  const size_t data = good.find("\ndata\n") + 6;
  ASSERT_LT(data, good.size());

  const std::string bad = dir + "/bad.bt";
  expectRejected(bad, "", "empty file");
  expectRejected(bad, "hello world\n", "not an octomap file");
  expectRejected(bad, "# Octomap OcTree binary file\nid OcTree\nsize 1\nres 0.1\n", "no data");
  expectRejected(bad, "# Octomap OcTree binary file\nid OcTree\nsize 1\nres -1\ndata\n\x01",
                 "negative resolution");
  expectRejected(bad, "# Octomap OcTree binary file\nid OcTree\nsize 1\nres abc\ndata\n",
                 "bad resolution");
  expectRejected(bad, "# Octomap OcTree binary file\nid OcTree\nsize -5\nres 0.1\ndata\n",
                 "bad size");
  std::string wrong_size = good;
  const size_t size_at = wrong_size.find("size ") + 5;
  wrong_size.insert(size_at, "1");  // "size N" -> "size 1N"
  expectRejected(bad, wrong_size, "size mismatch");
  // Inner-node flags all the way down: deeper than the tree's 16 levels.
  expectRejected(
      bad,
      "# Octomap OcTree binary file\nid OcTree\nsize 17\nres 0.1\ndata\n" + std::string(34, '\x03'),
      "too deep");
  // Every truncation of a valid file.
  for (size_t n = 0; n < good.size(); ++n) {
    writeBytes(bad, good.substr(0, n));
    EXPECT_THROW(importOctomap(bad), IoError) << "prefix of " << n << " bytes";
  }
  // Flipped data bytes: either a clear error or a map, never a crash.
  for (size_t i = data; i < good.size(); ++i) {
    std::string flipped = good;
    flipped[i] = static_cast<char>(flipped[i] ^ 0xff);
    writeBytes(bad, flipped);
    try {
      importOctomap(bad);
    } catch (const IoError&) {
    }
  }

  // .ot: truncation, unsupported tree types.
  ASSERT_TRUE(toOcTree(map)->write(dir + "/good.ot"));
  const std::string good_ot = readBytes(dir + "/good.ot");
  const std::string bad_ot = dir + "/bad.ot";
  for (size_t n : {size_t{0}, size_t{20}, good_ot.size() / 2, good_ot.size() - 1}) {
    writeBytes(bad_ot, good_ot.substr(0, n));
    EXPECT_THROW(importOctomap(bad_ot), IoError) << "prefix of " << n << " bytes";
  }
  std::string counting = good_ot;
  counting.replace(counting.find("id OcTree"), 9, "id CountingOcTree");
  expectRejected(bad_ot, counting, "unsupported tree type");
}

}  // namespace
}  // namespace fragg
