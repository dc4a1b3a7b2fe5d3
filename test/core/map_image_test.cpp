// Map::image + writeMapImage (map_image.h): the same bytes as Map::save, errors that leave the
// previous file, and the autosave kill test: a process saving in a loop, SIGKILLed at random
// moments (often mid-write), always leaves a file that loads and is one of the saved states.
#include "fragg_map/map_image.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "save_loop_scene.h"

namespace fragg {
namespace {
namespace fs = std::filesystem;

std::string tmpPath(const std::string& name) { return std::string(FRAGG_TEST_TMP) + "/" + name; }

std::vector<char> readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

Map mapOfScans(int scans) {
  Map map(test::saveLoopParams());
  for (int k = 0; k < scans; ++k) test::insertSaveLoopScan(map, k);
  return map;
}

/// Temporary files AtomicFile left beside `path` ("<name>.tmp.<pid>").
std::vector<fs::path> temporariesOf(const std::string& path) {
  std::vector<fs::path> found;
  const std::string prefix = fs::path(path).filename().string() + ".tmp.";
  for (const auto& e : fs::directory_iterator(fs::path(path).parent_path()))
    if (e.path().filename().string().rfind(prefix, 0) == 0) found.push_back(e.path());
  return found;
}

TEST(MapImageTest, WritesTheBytesOfSave) {
  Map map = mapOfScans(3);  // with kept scans
  SubmapRegion region = SubmapRegion::box({-1, -1, -1}, {1, 1, 1});
  region.frame_id = "map";
  map.setRegion(region);
  const std::string saved = tmpPath("image_save.fgm"), written = tmpPath("image_write.fgm");
  map.save(saved);
  const MapImage image = map.image();
  EXPECT_EQ(image.blocks.size(), map.blockCount());
  EXPECT_GT(image.bytes(), map.blockCount() * sizeof(Block));
  writeMapImage(image, written);
  EXPECT_EQ(readAll(saved), readAll(written));
  // The image is a copy: the map may change after it was taken.
  test::insertSaveLoopScan(map, 3);
  writeMapImage(image, written);
  EXPECT_EQ(readAll(saved), readAll(written));
  const Map loaded = Map::load(written, test::saveLoopParams());
  EXPECT_EQ(loaded.scanCount(), 3u);
  EXPECT_EQ(loaded.scanStore().size(), 3u);
}

TEST(MapImageTest, EmptyMapAndErrorsLeaveThePreviousFile) {
  const std::string path = tmpPath("image_errors.fgm");
  const Map empty(test::saveLoopParams());
  writeMapImage(empty.image(), path);
  EXPECT_EQ(Map::load(path).blockCount(), 0u);
  const std::vector<char> before = readAll(path);
  EXPECT_THROW(writeMapImage(MapImage(), path), InvalidArgument);
  EXPECT_THROW(writeMapImage(mapOfScans(1).image(), tmpPath("no_such_dir/x.fgm")), IoError);
  EXPECT_EQ(readAll(path), before);
  EXPECT_TRUE(temporariesOf(path).empty());
}

// A child process inserts and saves in a loop; it is killed at random moments. Every time the
// file at the path must load, and be byte for byte the map of the scan count it says it holds
// (one of the saved states), whether the kill came mid-write or between writes.
TEST(MapImageTest, KilledDuringSavesLeavesAValidSavedState) {
  const std::string path = tmpPath("image_kill.fgm");
  std::error_code ec;
  fs::remove(path, ec);
  for (const fs::path& t : temporariesOf(path)) fs::remove(t, ec);
  std::mt19937 rng(18);
  std::uniform_int_distribution<int> delay_ms(20, 300);
  int mid_write = 0, checked = 0, last_scans = 0;
  // 16 trials at random moments; then, if none of them landed mid-write (a loaded machine
  // can stretch the insert and shrink the chance), up to 48 more that watch for the
  // temporary file and kill as soon as it appears.
  constexpr int kRandomTrials = 16, kMaxTrials = 64;
  int trials = 0;
  for (int trial = 0; trial < kMaxTrials && (trial < kRandomTrials || mid_write == 0); ++trial) {
    ++trials;
    const bool aim_at_write = trial >= kRandomTrials;
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      execl(FRAGG_SAVE_LOOP, FRAGG_SAVE_LOOP, path.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    // The first trials wait for a first file; then kill at random moments.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (!fs::exists(path) && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    if (aim_at_write) {
      while (temporariesOf(path).empty() && std::chrono::steady_clock::now() < deadline) {
      }
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms(rng)));
    }
    ASSERT_EQ(kill(child, SIGKILL), 0);
    int status = 0;
    ASSERT_EQ(waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFSIGNALED(status)) << "the save loop ended by itself (status " << status << ")";
    const std::vector<fs::path> temporaries = temporariesOf(path);
    if (!temporaries.empty()) ++mid_write;
    for (const fs::path& t : temporaries) fs::remove(t, ec);
    ASSERT_TRUE(fs::exists(path));
    const Map loaded = Map::load(path, test::saveLoopParams());  // throws if not valid
    const int scans = static_cast<int>(loaded.scanCount());
    ASSERT_GE(scans, 1);
    // One of the saved states: the map of exactly that many scans, byte for byte (the checks
    // rebuild a few of them, the loads check every file's checksum).
    if (trial % 4 == 0 || trial == kRandomTrials - 1 || aim_at_write) {
      const std::string reference = tmpPath("image_kill_reference.fgm");
      mapOfScans(scans).save(reference);
      EXPECT_EQ(readAll(path), readAll(reference))
          << "trial " << trial << ", " << scans << " scans";
      ++checked;
    }
    last_scans = scans;
  }
  EXPECT_GE(checked, 5);
  EXPECT_GE(last_scans, 1);
  // At least one kill landed in a save, or the test proved nothing.
  EXPECT_GE(mid_write, 1) << "no kill landed during a write: the test proved nothing";
  std::printf("kill test: %d of %d kills left a partial temporary file\n", mid_write, trials);
}

}  // namespace
}  // namespace fragg
