// The server's autosave without a ROS master: autosave/* and file_root parsed and resolved
// (good and bad paths), the Autosaver's thread saving a changing map (and nothing while it does
// not change), the last save at destruction, and loadAutosave on a missing, a valid, a corrupt
// file and beside a killed save's temporary file.
#include "../../src/ros/server/autosave.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "fragg_map/errors.h"
#include "fragg_map/ros/autosave_params.h"
#include "fragg_map/ros/server_params.h"

namespace {

using fragg::ros::AutosaveParams;
using fragg::ros::Autosaver;
using fragg::ros::loadAutosave;
using fragg::ros::MapState;
using fragg::ros::parseAutosaveParameters;
using fragg::ros::resolveAutosavePath;
using fragg::ros::SharedMap;
using XmlRpc::XmlRpcValue;
namespace fs = std::filesystem;

std::string tmpDir(const std::string& name) {
  const std::string dir = std::string(FRAGG_TEST_TMP) + "/" + name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

fragg::MapParams mapParams() {
  fragg::MapParams p;
  p.backend = fragg::Backend::kCpu;
  p.threads = 1;
  return p;
}

void insertScan(SharedMap& shared, int k) {
  fragg::PointCloud cloud;
  for (int i = 0; i < 200; ++i)
    cloud.points_S.emplace_back(2.0f, -1.0f + 0.01f * i, 0.1f * (k % 7));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation().x() = 0.05 * k;
  shared.write()->map.insert(cloud, T, fragg::SensorModel::autoFromCloud());
}

bool waitFor(const std::function<bool()>& done, double seconds) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return done();
}

TEST(AutosaveParamsTest, ResolvesUnderFileRoot) {
  EXPECT_EQ(resolveAutosavePath("auto.fgm", "/data/maps"), "/data/maps/auto.fgm");
  EXPECT_EQ(resolveAutosavePath("a/../b/auto.fgm", "/data/maps/"), "/data/maps/b/auto.fgm");
  EXPECT_EQ(resolveAutosavePath("./sub/auto.fgm", "/data/maps"), "/data/maps/sub/auto.fgm");
  EXPECT_EQ(resolveAutosavePath("/var/x/../auto.fgm", "/data/maps"), "/var/auto.fgm");
  EXPECT_THROW(resolveAutosavePath("../auto.fgm", "/data/maps"), fragg::InvalidArgument);
  EXPECT_THROW(resolveAutosavePath("a/../../auto.fgm", "/data/maps"), fragg::InvalidArgument);
  EXPECT_THROW(resolveAutosavePath("", "/data/maps"), fragg::InvalidArgument);
  EXPECT_THROW(resolveAutosavePath("auto.bt", "/data/maps"), fragg::InvalidArgument);
  EXPECT_THROW(resolveAutosavePath("auto.fgm", "relative/root"), fragg::InvalidArgument);
}

TEST(AutosaveParamsTest, ParsesAndNamesTheBadParameter) {
  XmlRpcValue root;
  AutosaveParams p = parseAutosaveParameters(root);  // nothing given: no autosave
  EXPECT_FALSE(p.enabled());
  EXPECT_EQ(p.file_root, fragg::ros::defaultFileRoot());
  root["file_root"] = "/srv/maps";
  root["autosave"]["path"] = "robot/auto.fgm";
  root["autosave"]["period_s"] = 2;
  p = parseAutosaveParameters(root);
  EXPECT_EQ(p.path, "/srv/maps/robot/auto.fgm");
  EXPECT_EQ(p.period_s, 2.0);
  // The server's unknown-parameter check knows these names.
  EXPECT_TRUE(fragg::ros::parseParameters(root).unknown_parameters.empty());

  auto rejected = [](const std::string& name, XmlRpcValue root) {
    try {
      parseAutosaveParameters(root);
      ADD_FAILURE() << name << " accepted";
    } catch (const fragg::InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find("'" + name + "'"), std::string::npos) << e.what();
    }
  };
  XmlRpcValue bad = root;
  bad["autosave"]["period_s"] = -1.0;
  rejected("autosave/period_s", bad);
  bad = root;
  bad["autosave"]["period_s"] = "often";
  rejected("autosave/period_s", bad);
  bad = root;
  bad["autosave"]["path"] = "../../etc/auto.fgm";
  rejected("autosave/path", bad);
  bad = root;
  bad["autosave"]["path"] = 3;
  rejected("autosave/path", bad);
  bad = root;
  bad["file_root"] = "maps";
  rejected("file_root", bad);
  XmlRpcValue period_only;
  period_only["autosave"]["period_s"] = 1.0;
  rejected("autosave/period_s", period_only);
}

TEST(AutosaveParamsTest, DefaultFileRootIsUnderRosHome) {
  const char* old = std::getenv("ROS_HOME");
  const std::string saved = old ? old : "";
  setenv("ROS_HOME", "/tmp/some_ros_home", 1);
  EXPECT_EQ(fragg::ros::defaultFileRoot(), "/tmp/some_ros_home/fragg_map");
  if (old)
    setenv("ROS_HOME", saved.c_str(), 1);
  else
    unsetenv("ROS_HOME");
}

TEST(AutosaverTest, SavesWhileTheMapChangesAndOnDestruction) {
  const std::string dir = tmpDir("autosaver");
  AutosaveParams params;
  params.file_root = dir;
  params.path = dir + "/sub/auto.fgm";  // the folder is created
  params.period_s = 0.05;
  SharedMap shared{MapState(fragg::Map(mapParams()))};
  {
    Autosaver autosaver(params, &shared);
    for (int k = 0; k < 5; ++k) insertScan(shared, k);
    ASSERT_TRUE(waitFor([&] { return autosaver.saves() >= 1; }, 10));
    ASSERT_TRUE(waitFor(
        [&] {
          // A save of the five scans (the thread may have saved an earlier state first).
          try {
            return fragg::Map::load(params.path).scanCount() == 5;
          } catch (const fragg::IoError&) {
            return false;
          }
        },
        10));
    // Nothing changes: nothing is written.
    const uint64_t saves = autosaver.saves();
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    EXPECT_EQ(autosaver.saves(), saves);
    EXPECT_EQ(autosaver.failures(), 0u);
    insertScan(shared, 5);
    autosaver.saveNow();
    EXPECT_FALSE(autosaver.saveNow());  // unchanged since the save above
  }
  insertScan(shared, 6);
  {
    params.period_s = 0;  // on destruction only
    Autosaver autosaver(params, &shared);
    EXPECT_EQ(fragg::Map::load(params.path).scanCount(), 6u);
  }
  const fragg::Map saved = fragg::Map::load(params.path);
  EXPECT_EQ(saved.scanCount(), 7u);
  EXPECT_EQ(saved.knownVoxelCount(), shared.read()->map.knownVoxelCount());
}

TEST(AutosaverTest, FailuresAreCountedNotThrown) {
  const std::string dir = tmpDir("autosaver_fail");
  AutosaveParams params;
  params.file_root = dir;
  params.path = dir + "/auto.fgm";
  SharedMap shared{MapState(fragg::Map(mapParams()))};
  Autosaver autosaver(params, &shared);
  insertScan(shared, 0);
  fs::create_directory(params.path);  // a folder where the file should go: rename fails
  EXPECT_FALSE(autosaver.saveNow());
  EXPECT_EQ(autosaver.failures(), 1u);
  fs::remove(params.path);
  EXPECT_TRUE(autosaver.saveNow());
  EXPECT_EQ(fragg::Map::load(params.path).scanCount(), 1u);
}

TEST(AutosaveLoadTest, MissingValidCorruptAndLeftovers) {
  const std::string dir = tmpDir("autosave_load");
  const std::string path = dir + "/auto.fgm";
  EXPECT_FALSE(loadAutosave(path, mapParams()).has_value());
  SharedMap shared{MapState(fragg::Map(mapParams()))};
  for (int k = 0; k < 3; ++k) insertScan(shared, k);
  shared.read()->map.save(path);
  std::ofstream(path + ".tmp.12345") << "half a map";  // a save killed mid-write
  const std::optional<fragg::Map> loaded = loadAutosave(path, mapParams());
  ASSERT_TRUE(loaded.has_value());
  EXPECT_EQ(loaded->scanCount(), 3u);
  EXPECT_FALSE(fs::exists(path + ".tmp.12345"));
  fragg::MapParams other = mapParams();
  other.resolution_m = 0.2;
  EXPECT_THROW(loadAutosave(path, other), fragg::InvalidArgument);
  fs::resize_file(path, fs::file_size(path) - 10);
  try {
    loadAutosave(path, mapParams());
    FAIL() << "a truncated autosave was loaded";
  } catch (const fragg::IoError& e) {
    EXPECT_NE(std::string(e.what()).find("move the file away"), std::string::npos) << e.what();
  }
}

}  // namespace
