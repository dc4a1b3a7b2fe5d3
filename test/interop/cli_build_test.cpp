// The fragg_map tool's build and stats subcommands, run as a user would: real input, JSON
// output, and bad arguments or input (one-line error, exit code, no file left behind).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "interop_test_util.h"

namespace fragg {
namespace {

using test::fileExists;
using test::listDir;
using test::readBytes;
using test::runCli;
using test::testDir;
using test::writeBytes;

const std::string kPly = std::string(FRAGG_REAL_DATA) + "/small_gicp_pair/target.ply";

TEST(CliBuild, BuildsARealScanAndStatsAgrees) {
  const std::string dir = testDir();
  const std::string map = dir + "/velodyne.fgm";
  auto r =
      runCli(dir, "build '" + kPly + "' -o '" + map + "' --resolution 0.1 --max-range 30 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json b = nlohmann::json::parse(r.out);
  EXPECT_EQ(b["scans"], 1);
  EXPECT_EQ(b["points"], 69088);
  EXPECT_EQ(b["dropped_invalid"], 5032);  // the scan's (0, 0, 0) no-return points
  EXPECT_GT(b["known_voxels"].get<int64_t>(), 100000);
  EXPECT_EQ(b["backend"], "cpu");
  ASSERT_TRUE(fileExists(map));

  r = runCli(dir, "stats '" + map + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json s = nlohmann::json::parse(r.out);
  EXPECT_EQ(s["known_voxels"], b["known_voxels"]);
  EXPECT_EQ(s["scans"], 1);
  EXPECT_DOUBLE_EQ(s["resolution_m"].get<double>(), 0.1);
  EXPECT_GT(s["occupied"].get<int64_t>(), 1000);
  EXPECT_GT(s["free"].get<int64_t>(), s["occupied"].get<int64_t>());

  // Without --json: one summary line naming the output.
  r = runCli(dir, "build '" + kPly + "' -o '" + map + "' --resolution 0.1 --max-range 30");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("built " + map + ": 1 scans, 69088 points", 0), 0u) << r.out;
}

TEST(CliBuild, ExplicitSensorReportsPointsOutsideItsFrustum) {
  const std::string dir = testDir();
  // A forward-looking 90 x 40 degree camera model cannot hold a 360-degree scan.
  auto r = runCli(dir, "build '" + kPly + "' -o '" + dir +
                           "/m.fgm' --resolution 0.2 --sensor "
                           "pinhole --hfov 90 --vfov 40 --optical-axis x --max-range 30 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_GT(nlohmann::json::parse(r.out)["dropped_outside_frustum"].get<int64_t>(), 30000);
  EXPECT_NE(r.err.find("outside"), std::string::npos) << r.err;
}

TEST(CliBuild, BadArgumentsAndInputsFailCleanly) {
  const std::string dir = testDir();
  writeBytes(dir + "/truncated.ply", readBytes(kPly).substr(0, 5000));
  writeBytes(dir + "/corrupt.fgm", "FRAGGMAP not really\n");
  const std::string out = dir + "/out";
  ASSERT_EQ(std::system(("mkdir -p '" + out + "'").c_str()), 0);
  struct Case {
    std::string args;
    int exit_code;
    std::string says;
  };
  const Case cases[] = {
      {"build '" + dir + "/missing.ply' -o '" + out + "/m.fgm'", 1, "no such file"},
      {"build '" + dir + "/truncated.ply' -o '" + out + "/m.fgm'", 1, "truncated.ply"},
      {"build '" + kPly + "' -o '" + out + "/m.fgm' --resolution -1", 2, "resolution"},
      {"build '" + kPly + "' -o '" + out + "/m.fgm' --resolution nan", 2, "resolution"},
      {"build '" + kPly + "' -o '" + out + "/m.bt'", 2, ".fgm"},
      {"build '" + kPly + "' -o '" + dir + "/no_such_dir/m.fgm'", 1, "no_such_dir"},
      {"build '" + kPly + "' -o '" + out + "/m.fgm' --sensor pinhole", 2, "--hfov"},
      {"build '" + kPly + "' -o '" + out + "/m.fgm' --sensor sonar", 2, "sensor"},
      {"build '" + kPly + "' -o '" + out + "/m.fgm' --backend cuda", 2, "CUDA"},
      {"build '" + kPly + "' -o '" + out + "/m.fgm' --hit 0.3", 2, "hit"},
      {"build '" + kPly + "' -o '" + out + "/m.fgm' --min-range 5 --max-range 2", 2, "range"},
      {"build '" + kPly + "' -o '" + out + "/m.fgm' --range-noise -0.02", 2, "--range-noise must"},
      {"build '" + kPly + "' -o '" + out + "/m.fgm' --range-noise-quadratic 5", 2,
       "--range-noise-quadratic must"},
      {"build '" + kPly + "' -o '" + out + "/m.fgm' --min-z 2 --max-z 1", 2,
       "--min-z (2.000000 m) must not exceed --max-z"},
      {"build '" + kPly + "' -o '" + out + "/m.fgm' --clamp-min 0.98", 2,
       "--clamp-min must be below --clamp-max"},
      {"build '" + kPly + "' -o '" + out + "/m.fgm' --dynamic --dynamic-rule sideways", 2,
       "--dynamic-rule must be pass-through or surround, got 'sideways'"},
      {"build '" + kPly + "' -o '" + out +
           "/m.fgm' --clear-no-return --sensor lidar --elevation-min -15 --elevation-max 15 "
           "--lidar-height 16",
       2, "--lidar-width must be in [1, 100000], got 0"},
      {"build '" + kPly + "' -o '" + out + "/m.fgm' --lidar-height 16 --lidar-width 1800", 2,
       "--lidar-height spaces its rings over --sensor lidar's"},
      {"build '" + kPly + "' -o '" + out +
           "/m.fgm' --lidar-ring-elevations 2,-2,5 --lidar-width 1800",
       2, "--lidar-ring-elevations must increase strictly"},
      {"build '" + kPly + "'", 2, "output"},
      {"stats '" + dir + "/missing.fgm'", 1, "missing.fgm"},
      {"stats '" + dir + "/corrupt.fgm'", 1, "corrupt.fgm"},
      {"stats", 2, "map"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.args);
    const auto r = runCli(dir, c.args);
    EXPECT_EQ(r.exit_code, c.exit_code) << r.err;
    EXPECT_EQ(r.err.rfind("fragg_map: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_TRUE(listDir(out).empty()) << "left behind: " << listDir(out).front();
  }
}

TEST(CliBuild, ExtremeFinitePointsNeverEndTheBuildBySignal) {
  // Issue 39: one finite point (a huge coordinate with a tiny non-zero other one) killed
  // `fragg_map build` with SIGSEGV. Each of these, beside ordinary points, at 5 and 20 cm with
  // max range 20, 80 and none: exit 0 and every point counted. (The default backend: the CUDA
  // one where a device is present.)
  const char* kPoints[] = {"3.7e27 -4e-20 -3.7e27", "-3.7e27 4e-20 3.7e27", "4e-20 3.7e27 -3.7e27",
                           "3.4e38 1e-30 -3.4e38",  "1e30 1e30 1e30",       "1e-45 1e-45 1e-45",
                           "1e19 -1e-38 1e19",      "20 1e-40 -20",         "1e15 1e15 -1e-25",
                           "3e38 3e38 3e38"};
  const std::string dir = testDir();
  const std::string xyz = dir + "/p.xyz", map = dir + "/p.fgm";
  for (const char* point : kPoints) {
    writeBytes(xyz, std::string(point) + "\n1.5 0.2 0.1\n-2 1 0.5\n0.3 -4 -0.2\n");
    for (const char* res : {"0.05", "0.2"}) {
      for (const char* range : {" --max-range 20", " --max-range 80", ""}) {
        SCOPED_TRACE(std::string(point) + " at " + res + range);
        const auto r = runCli(
            dir, "build '" + xyz + "' -o '" + map + "' --resolution " + res + range + " --json");
        ASSERT_EQ(r.exit_code, 0) << r.err;
        const nlohmann::json b = nlohmann::json::parse(r.out);
        EXPECT_EQ(b["points"], 4);
        const int counted = b["rays_hit"].get<int>() + b["rays_free_only"].get<int>() +
                            b["dropped_invalid"].get<int>() + b["dropped_min_range"].get<int>();
        EXPECT_EQ(counted, 4) << r.out;
        EXPECT_GE(b["rays_hit"].get<int>(), 3) << r.out;
      }
    }
  }
}

}  // namespace
}  // namespace fragg
