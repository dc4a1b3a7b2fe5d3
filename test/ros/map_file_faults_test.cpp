// The server's map files under faults (what ~load_map and ~save_map meet): corrupt and foreign
// files are refused with an error and no crash; a save that runs out of space (a full tmpfs,
// or a file size limit) fails with IoError, leaves the previous file valid and no temporary
// file behind, and the map unchanged.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>

#include "../../src/ros/server/map_file_loader.h"
#include "fragg_map/errors.h"
#include "fragg_map/interop/octomap_io.h"
#include "fragg_map/map_image.h"
#include "map_fixtures.h"

namespace {

namespace fs = std::filesystem;
using fragg::ros::loadMapFile;

fs::path tmpDir(const std::string& name) {
  const fs::path dir = fs::path(FRAGG_TEST_TMP) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string readAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void writeAll(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

fragg::MapParams params() {
  fragg::MapParams p = fragg::ros::test::cpuParams(0.1);
  p.scans.keep = true;
  return p;
}

// A map of a few walls: its .fgm and .bt are over 16 KiB (checked where it matters).
fragg::Map bigMap() {
  fragg::Map map(params());
  for (double x = -6.0; x <= 6.0; x += 1.5)
    for (double y = -6.0; y <= 6.0; y += 6.0)
      fragg::ros::test::insertWall(map, Eigen::Vector3d(x, y, 0.5), 4.0);
  return map;
}

// Loading `path` fails with IoError or InvalidArgument (anything else, or success, fails).
void expectRefused(const fs::path& path, const std::string& what) {
  try {
    loadMapFile(path.string(), params());
    ADD_FAILURE() << what << ": loaded";
  } catch (const fragg::IoError& e) {
    EXPECT_TRUE(std::strlen(e.what()) > 0) << what;
  } catch (const fragg::InvalidArgument& e) {
    EXPECT_TRUE(std::strlen(e.what()) > 0) << what;
  } catch (const std::exception& e) {
    ADD_FAILURE() << what << ": an exception of another type: " << e.what();
  }
}

TEST(MapFileFaults, CorruptAndForeignFilesAreRefused) {
  const fs::path dir = tmpDir("map_file_faults_corrupt");
  const fragg::Map map = bigMap();
  map.save((dir / "good.fgm").string());
  fragg::exportOctomap(map, (dir / "good.bt").string());
  const std::string fgm = readAll(dir / "good.fgm");
  const std::string bt = readAll(dir / "good.bt");
  ASSERT_GT(fgm.size(), 1000u);

  writeAll(dir / "empty.fgm", "");
  expectRefused(dir / "empty.fgm", "an empty .fgm");
  writeAll(dir / "text.fgm", "hello, this is not a map\n");
  expectRefused(dir / "text.fgm", "text named .fgm");
  writeAll(dir / "octree.fgm", bt);
  expectRefused(dir / "octree.fgm", "an OcTree named .fgm");
  writeAll(dir / "fgm.bt", fgm);
  expectRefused(dir / "fgm.bt", "a .fgm named .bt");
  writeAll(dir / "text.bt", "# Octomap OcTree binary file\nid OcTree\nsize 99999\nres 0.1\ndata\n");
  expectRefused(dir / "text.bt", "a .bt header with no data");
  std::mt19937 rng(18);
  std::string noise(fgm.size(), '\0');
  for (char& c : noise) c = static_cast<char>(rng());
  writeAll(dir / "noise.fgm", noise);
  expectRefused(dir / "noise.fgm", "random bytes");
  for (const size_t keep : {size_t{8}, size_t{64}, fgm.size() / 2, fgm.size() - 1}) {
    writeAll(dir / "short.fgm", fgm.substr(0, keep));
    expectRefused(dir / "short.fgm", "the .fgm cut at byte " + std::to_string(keep));
  }
  for (const size_t at : {fgm.size() / 3, fgm.size() / 2, fgm.size() - 5}) {
    std::string flipped = fgm;
    flipped[at] = static_cast<char>(flipped[at] ^ 0x5a);
    writeAll(dir / "flipped.fgm", flipped);
    expectRefused(dir / "flipped.fgm", "a byte flipped at " + std::to_string(at));
  }
  fs::create_directories(dir / "folder.fgm");
  expectRefused(dir / "folder.fgm", "a folder named .fgm");
  // The good ones still load.
  EXPECT_EQ(loadMapFile((dir / "good.fgm").string(), params()).knownVoxelCount(),
            map.knownVoxelCount());
}

// Saves `map` over `path` (which holds `previous`, a valid smaller map) where space runs out
// (.fgm: both Map::save and writeMapImage of Map::image, ~save_map's way):
// IoError, the old file intact and loadable, no temporary file, the map unchanged.
void expectFailedSaveKeepsTheOldFile(const fragg::Map& map, const fs::path& path,
                                     const fragg::Map& previous, bool bt) {
  const std::string before = readAll(path);
  const size_t known = map.knownVoxelCount();
  const uint64_t revision = map.revision();
  if (bt) {
    EXPECT_THROW(fragg::exportOctomap(map, path.string()), fragg::IoError);
  } else {
    EXPECT_THROW(map.save(path.string()), fragg::IoError);
    // ~save_map's and the autosave's way: the image taken, then written without the map.
    EXPECT_THROW(fragg::writeMapImage(map.image(), path.string()), fragg::IoError);
  }
  EXPECT_EQ(readAll(path), before);
  for (const auto& entry : fs::directory_iterator(path.parent_path()))
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos)
        << "left behind: " << entry.path();
  EXPECT_EQ(map.knownVoxelCount(), known);
  EXPECT_EQ(map.revision(), revision);
  EXPECT_EQ(loadMapFile(path.string(), params()).knownVoxelCount(), previous.knownVoxelCount());
}

fragg::Map smallMap() {
  fragg::Map map(params());
  fragg::ros::test::insertWall(map, Eigen::Vector3d(0.0, 0.0, 0.5), 1.0);
  return map;
}

TEST(MapFileFaults, SaveOnAFullTmpfsFailsAndKeepsThePreviousFile) {
  if (geteuid() != 0) GTEST_SKIP() << "not root: cannot mount a small tmpfs here";
  const fs::path dir = tmpDir("map_file_faults_tmpfs");
  const fragg::Map big = bigMap();
  const fragg::Map small = smallMap();
  // Both small files fit in the 4 pages; the big map's files do not.
  const fs::path probe = tmpDir("map_file_faults_sizes");
  big.save((probe / "big.fgm").string());
  fragg::exportOctomap(big, (probe / "big.bt").string());
  ASSERT_GT(fs::file_size(probe / "big.fgm"), 16384u);
  ASSERT_GT(fs::file_size(probe / "big.bt"), 16384u);
  if (mount("tmpfs", dir.c_str(), "tmpfs", 0, "size=16k") != 0)
    GTEST_SKIP() << "mounting a 16 KiB tmpfs is not permitted here (" << std::strerror(errno)
                 << "); the file size limit test covers the same path";
  {
    small.save((dir / "map.fgm").string());
    fragg::exportOctomap(small, (dir / "map.bt").string());
    expectFailedSaveKeepsTheOldFile(big, dir / "map.fgm", small, false);
    expectFailedSaveKeepsTheOldFile(big, dir / "map.bt", small, true);
  }
  EXPECT_EQ(umount(dir.c_str()), 0) << std::strerror(errno);
}

TEST(MapFileFaults, SaveBeyondTheFileSizeLimitFailsAndKeepsThePreviousFile) {
  const fs::path dir = tmpDir("map_file_faults_fsize");
  const fragg::Map big = bigMap();
  const fragg::Map small = smallMap();
  small.save((dir / "map.fgm").string());
  fragg::exportOctomap(small, (dir / "map.bt").string());
  ASSERT_LT(fs::file_size(dir / "map.fgm"), 8192u);
  ASSERT_LT(fs::file_size(dir / "map.bt"), 8192u);
  big.save((dir / "big.fgm").string());
  fragg::exportOctomap(big, (dir / "big.bt").string());
  ASSERT_GT(fs::file_size(dir / "big.fgm"), 8192u);
  ASSERT_GT(fs::file_size(dir / "big.bt"), 8192u);
  fs::remove(dir / "big.fgm");
  fs::remove(dir / "big.bt");
  // Writes past 8 KiB fail with EFBIG (SIGXFSZ ignored), as a full disk fails with ENOSPC.
  struct sigaction ignore {
  }, old_action{};
  ignore.sa_handler = SIG_IGN;
  ASSERT_EQ(sigaction(SIGXFSZ, &ignore, &old_action), 0);
  rlimit old_limit{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  rlimit limit = old_limit;
  limit.rlim_cur = 8192;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limit), 0);
  expectFailedSaveKeepsTheOldFile(big, dir / "map.fgm", small, false);
  expectFailedSaveKeepsTheOldFile(big, dir / "map.bt", small, true);
  EXPECT_EQ(setrlimit(RLIMIT_FSIZE, &old_limit), 0);
  EXPECT_EQ(sigaction(SIGXFSZ, &old_action, nullptr), 0);
  // With room again the same save works.
  big.save((dir / "map.fgm").string());
  EXPECT_EQ(loadMapFile((dir / "map.fgm").string(), params()).knownVoxelCount(),
            big.knownVoxelCount());
}

}  // namespace
