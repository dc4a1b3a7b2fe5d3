// `fragg_map truncate` and `fragg_map merge`, run as a user would, with good and bad input
// (one-line error, exit code 2 for bad arguments and 1 for bad files, no output left behind).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "interop_test_util.h"
#include "submap_scenes.h"

namespace fragg {
namespace {

using test::fileExists;
using test::runCli;
using test::testDir;

std::string q(const std::string& path) { return "'" + path + "'"; }

/// The loop tests' room, saved; returns the path.
std::string savedRoom(const std::string& dir, double resolution_m = 0.05) {
  const std::string path = dir + "/room" + std::to_string(int(resolution_m * 100)) + ".fgm";
  test::roomMap(test::cpuParams(resolution_m)).save(path);
  return path;
}

void expectOneLineError(const test::RunResult& r, int code, const std::string& needle) {
  EXPECT_EQ(r.exit_code, code) << r.err;
  EXPECT_EQ(r.err.rfind("fragg_map: error: ", 0), 0u) << r.err;
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << r.err;
}

TEST(CliSubmap, TruncateBoxAndMergeBackGiveTheMap) {
  const std::string dir = testDir();
  const std::string map = savedRoom(dir);
  auto r = runCli(dir, "truncate " + q(map) + " --box -1 -1.2 -0.5 1.5 1 1.03 -o " +
                           q(dir + "/sub.fgm") + " --rest " + q(dir + "/rest.fgm") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_GT(j["cells_moved"].get<uint64_t>(), 10000u);
  EXPECT_GT(j["blocks_moved"].get<uint64_t>(), 10u);
  EXPECT_EQ(j["region"], "box");
  const Map sub = Map::load(dir + "/sub.fgm", Backend::kCpu);
  EXPECT_EQ(sub.region().kind, SubmapRegion::Kind::kBox);
  EXPECT_EQ(sub.region().max_map, Eigen::Vector3d(1.5, 1, 1.03));
  EXPECT_EQ(sub.knownVoxelCount(), j["cells_moved"].get<uint64_t>());

  r = runCli(dir, "merge " + q(dir + "/rest.fgm") + " " + q(dir + "/sub.fgm") + " -o " +
                      q(dir + "/back.fgm") + " --mode overwrite --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["cells_merged"], j["cells_moved"]);
  std::string why;
  EXPECT_TRUE(test::sameCells(Map::load(dir + "/back.fgm", Backend::kCpu),
                              Map::load(map, Backend::kCpu), &why))
      << why;
}

TEST(CliSubmap, TruncateRadiusAndMergeWithAddAndTransform) {
  const std::string dir = testDir();
  const std::string map = savedRoom(dir);
  auto r = runCli(dir, "truncate " + q(map) + " --center 0.3 0.1 0.5 --radius 2.5 -o " +
                           q(dir + "/far.fgm") + " --rest " + q(dir + "/near.fgm"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("moved ", 0), 0u) << r.out;
  const Map far = Map::load(dir + "/far.fgm", Backend::kCpu);
  size_t near_cells = 0;
  test::forEachObserved(far, [&](const VoxelKey& k, const Cell&) {
    near_cells += (far.centerOf(k) - Eigen::Vector3d(0.3, 0.1, 0.5)).norm() > 2.5 ? 0 : 1;
  });
  EXPECT_EQ(near_cells, 0u);
  // Disjoint halves: add is overwrite.
  r = runCli(dir, "merge " + q(dir + "/near.fgm") + " " + q(dir + "/far.fgm") + " -o " +
                      q(dir + "/back.fgm") + " --mode add");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(
      test::sameCells(Map::load(dir + "/back.fgm", Backend::kCpu), Map::load(map, Backend::kCpu)));
  // A whole-voxel translation moves every cell by 3 voxels in x.
  r = runCli(dir, "merge " + q(dir + "/near.fgm") + " " + q(dir + "/far.fgm") + " -o " +
                      q(dir + "/moved.fgm") +
                      " --mode overwrite --json --transform 0.15 0 0 0 0 0 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Map moved = Map::load(dir + "/moved.fgm", Backend::kCpu);
  test::forEachObserved(far, [&](const VoxelKey& k, const Cell& c) {
    ASSERT_TRUE(test::sameCell(test::cellAt(moved, {k.x + 3, k.y, k.z}), c));
  });
}

TEST(CliSubmap, BadArgumentsAreRefused) {
  const std::string dir = testDir();
  const std::string map = savedRoom(dir);
  const std::string out = " -o " + q(dir + "/out.fgm");
  expectOneLineError(runCli(dir, "truncate " + q(map) + out), 2, "--box");
  expectOneLineError(
      runCli(dir, "truncate " + q(map) + " --box 0 0 0 1 1 1 --center 0 0 0 --radius 1" + out), 2,
      "either");
  expectOneLineError(runCli(dir, "truncate " + q(map) + " --center 0 0 0" + out), 2, "--radius");
  expectOneLineError(runCli(dir, "truncate " + q(map) + " --box 1 0 0 0 1 1" + out), 2,
                     "min corner");
  expectOneLineError(runCli(dir, "truncate " + q(map) + " --box nan 0 0 1 1 1" + out), 2, "finite");
  expectOneLineError(runCli(dir, "truncate " + q(map) + " --center 0 0 0 --radius -1" + out), 2,
                     "radius");
  expectOneLineError(runCli(dir, "truncate " + q(map) + " --box 0 0 0 1 1 1 -o x.ply"), 2, ".fgm");
  expectOneLineError(runCli(dir, "merge " + q(map) + " " + q(map) + out + " --mode sum"), 2,
                     "overwrite or add");
  expectOneLineError(runCli(dir, "merge " + q(map) + " " + q(map) + out +
                                     " --mode add --transform 0 0 0 0 0 0 1.01"),
                     2, "quaternion");
  expectOneLineError(
      runCli(dir, "merge " + q(map) + " " + q(savedRoom(dir, 0.1)) + out + " --mode add"), 2,
      "resolution");
  EXPECT_FALSE(fileExists(dir + "/out.fgm"));
}

TEST(CliSubmap, UnreadableSubMapsAreRejected) {
  const std::string dir = testDir();
  const std::string map = savedRoom(dir);
  const std::string out = " -o " + q(dir + "/out.fgm");
  expectOneLineError(
      runCli(dir, "merge " + q(map) + " " + q(dir + "/missing.fgm") + out + " --mode add"), 1,
      "missing.fgm");
  // A sub-map whose bytes were damaged: the loader's checksum rejects it.
  std::string bytes = test::readBytes(map);
  bytes[bytes.size() / 2] ^= 0x21;
  test::writeBytes(dir + "/corrupt.fgm", bytes);
  expectOneLineError(
      runCli(dir, "merge " + q(map) + " " + q(dir + "/corrupt.fgm") + out + " --mode overwrite"), 1,
      "checksum");
  test::writeBytes(dir + "/short.fgm", bytes.substr(0, 40));
  expectOneLineError(
      runCli(dir, "merge " + q(map) + " " + q(dir + "/short.fgm") + out + " --mode overwrite"), 1,
      "too short");
  EXPECT_FALSE(fileExists(dir + "/out.fgm"));
}

}  // namespace
}  // namespace fragg
