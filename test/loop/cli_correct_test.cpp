// `fragg_map build --keep-scans`, `stats --scans` and `correct`, run as a user would, with
// good and bad input (one-line error, exit code, no output file left behind).
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "interop_test_util.h"

namespace fragg {
namespace {

using test::fileExists;
using test::runCli;
using test::testDir;

const std::string kRgbd = std::string(FRAGG_REAL_DATA) + "/slambook2_ch5_rgbd";

/// Builds the five RGB-D frames with their scans kept; returns the map path.
std::string buildKept(const std::string& dir, bool keep = true) {
  const std::string map = dir + (keep ? "/kept.fgm" : "/plain.fgm");
  const auto r = runCli(dir, "build '" + kRgbd + "' -o '" + map + "' --resolution 0.05" +
                                 (keep ? " --keep-scans" : "") + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  if (keep) {
    EXPECT_EQ(nlohmann::json::parse(r.out)["kept_scans"], 5);
  }
  return map;
}

void writeText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

/// "index tx ty tz qx qy qz qw" of a kept scan, from `stats --json --scans`, moved by dx.
std::string poseLine(const nlohmann::json& scan, double dx) {
  const auto& p = scan["pose"];
  return std::to_string(scan["index"].get<int>()) + " " + std::to_string(p[0].get<double>() + dx) +
         " " + std::to_string(p[1].get<double>()) + " " + std::to_string(p[2].get<double>()) + " " +
         std::to_string(p[3].get<double>()) + " " + std::to_string(p[4].get<double>()) + " " +
         std::to_string(p[5].get<double>()) + " " + std::to_string(p[6].get<double>()) + "\n";
}

double agreement(const std::string& dir, const std::string& a, const std::string& b) {
  const auto r = runCli(dir, "compare '" + a + "' '" + b + "' --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return nlohmann::json::parse(r.out)["agreement_in_either"].get<double>();
}

TEST(CliCorrect, MovesScansAndBack) {
  const std::string dir = testDir();
  const std::string map = buildKept(dir);
  auto r = runCli(dir, "stats '" + map + "' --json --scans");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json scans = nlohmann::json::parse(r.out)["scan_list"];
  ASSERT_EQ(scans.size(), 5u);
  EXPECT_EQ(scans[3]["index"], 3);
  EXPECT_EQ(scans[3]["points"], 640 * 480);

  // Move scans 3 and 4 by 0.25 m: the map changes.
  writeText(dir + "/moved.txt",
            "# two scans off\n" + poseLine(scans[3], 0.25) + poseLine(scans[4], 0.25));
  r = runCli(dir, "correct '" + map + "' --poses '" + dir + "/moved.txt' -o '" + dir +
                      "/moved.fgm' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json c = nlohmann::json::parse(r.out);
  EXPECT_EQ(c["scans_corrected"], 2);
  EXPECT_GT(c["cells_removed"].get<int64_t>(), 100000);
  EXPECT_LT(agreement(dir, map, dir + "/moved.fgm"), 0.97);

  // And back (the text format prints 6 decimals: poses agree to a micrometre): the corrected
  // map is the original again, up to clamping (OccupancyModel::unapply).
  writeText(dir + "/back.txt", poseLine(scans[3], 0.0) + poseLine(scans[4], 0.0));
  r = runCli(dir, "correct '" + dir + "/moved.fgm' --poses '" + dir + "/back.txt' -o '" + dir +
                      "/back.fgm'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("corrected 2 of 5 kept scans", 0), 0u) << r.out;
  EXPECT_GE(agreement(dir, map, dir + "/back.fgm"), 0.995);

  // `stats --scans` prints a file `correct --poses` reads as it is.
  r = runCli(dir, "stats '" + map + "' --scans");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  writeText(dir + "/listed.txt", r.out);
  r = runCli(dir,
             "correct '" + map + "' --poses '" + dir + "/listed.txt' -o '" + dir + "/listed.fgm'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("corrected 5 of 5 kept scans", 0), 0u) << r.out;
}

TEST(CliCorrect, KeptScansDoNotChangeTheMapUnlessQuantised) {
  // A real Velodyne scan, 5 cm: `--keep-scans` keeps float32 points and the map is the one
  // built without it, cell for cell; `--scan-step 0.001` halves the kept bytes but the map is
  // built from the quantised points and differs in some cells (1.3 % measured: the scan
  // reaches ~78 m, so its step widens beyond 1 mm to fit 16 bits).
  const std::string dir = testDir();
  const std::string ply = std::string(FRAGG_REAL_DATA) + "/small_gicp_pair/target.ply";
  auto build = [&](const std::string& name, const std::string& options) {
    const auto r = runCli(dir, "build '" + ply + "' -o '" + dir + "/" + name +
                                   "' --resolution 0.05 --max-range 30 --json" + options);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r.exit_code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json::object();
  };
  const nlohmann::json plain = build("plain.fgm", "");
  const nlohmann::json kept = build("kept.fgm", " --keep-scans");
  const nlohmann::json step = build("step.fgm", " --keep-scans --scan-step 0.001");
  ASSERT_FALSE(kept.empty());
  ASSERT_FALSE(step.empty());
  const int64_t points = plain["points"].get<int64_t>();  // every point of the cloud is kept
  EXPECT_EQ(kept["scan_store_bytes"].get<int64_t>(), points * 12);
  EXPECT_EQ(step["scan_store_bytes"].get<int64_t>(), points * 6);
  EXPECT_EQ(plain["known_voxels"], kept["known_voxels"]);
  auto compare = [&](const std::string& a, const std::string& b) {
    const auto r = runCli(dir, "compare '" + dir + "/" + a + "' '" + dir + "/" + b + "' --json");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(r.out);
  };
  const nlohmann::json same = compare("plain.fgm", "kept.fgm");
  EXPECT_GT(same["known_in_either"].get<int64_t>(), 100000);
  EXPECT_EQ(same["agreeing"], same["known_in_either"]);
  const nlohmann::json quantised = compare("plain.fgm", "step.fgm");
  EXPECT_LT(quantised["agreeing"].get<int64_t>(), quantised["known_in_either"].get<int64_t>());
  EXPECT_GT(quantised["agreement_in_either"].get<double>(), 0.95);  // still the same scene
}

TEST(CliCorrect, BadInputFailsWithOneLineAndWritesNothing) {
  const std::string dir = testDir();
  const std::string map = buildKept(dir);
  const std::string plain = buildKept(dir, false);
  const std::string out = dir + "/out.fgm";
  struct Case {
    std::string poses_text, map, expect;
    int exit_code;
  };
  const Case cases[] = {
      {"9 0 0 0 0 0 0 1\n", map, "no kept scan with index 9", 2},
      {"1 nan 0 0 0 0 0 1\n", map, "not a finite number", 1},
      {"1 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n", map, "listed twice", 1},
      {"1 0 0 0 0 0 0\n", map, "expected 'scan_index tx ty tz qx qy qz qw'", 1},
      {"-1 0 0 0 0 0 0 1\n", map, "is not a scan index", 1},
      {"1 0 0 0 0 0 0 5\n", map, "quaternion", 1},
      {"1 0 0 0 0 0 0 1\n", plain, "keeps no scans", 2},
  };
  for (const Case& k : cases) {
    writeText(dir + "/p.txt", k.poses_text);
    const auto r =
        runCli(dir, "correct '" + k.map + "' --poses '" + dir + "/p.txt' -o '" + out + "'");
    EXPECT_EQ(r.exit_code, k.exit_code) << k.poses_text << r.err;
    EXPECT_NE(r.err.find(k.expect), std::string::npos) << k.poses_text << r.err;
    EXPECT_FALSE(fileExists(out)) << k.poses_text;
  }
  const auto r =
      runCli(dir, "correct '" + map + "' --poses '" + dir + "/none.txt' -o '" + out + "'");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_FALSE(fileExists(out));
}

}  // namespace
}  // namespace fragg
