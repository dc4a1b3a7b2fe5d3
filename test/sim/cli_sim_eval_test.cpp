// The fragg_map_sim and fragg_map eval / octomap-build tools, run as a user would, on the smoke
// workload the build generates (cmake/sim_workloads.cmake): good runs and bad arguments.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

#include "sim_test_util.h"

namespace fragg::sim {
namespace {

const std::string kSmoke = std::string(FRAGG_SMOKE_DIR) + "/smoke";
const std::string kCampusObj = std::string(FRAGG_SMOKE_DIR) + "/campus.obj";
const std::string kScenes = FRAGG_SCENES_DIR;

test::RunResult cli(const std::string& dir, const std::string& args) {
  return test::run(FRAGG_CLI_PATH, dir, args);
}

TEST(CliEval, SmokeMapScoresWellAgainstTheSceneAndAsWellAsOctomap) {
  const std::string dir = test::testDir();
  auto r = cli(dir, "build '" + kSmoke + "' -o '" + dir + "/m.fgm' --max-range 15 --scans 2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::string octomap;
#ifdef FRAGG_CLI_HAS_OCTOMAP
  r = cli(dir, "octomap-build '" + kSmoke + "' -o '" + dir + "/m.bt' --max-range 15 --scans 2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  octomap = " --octomap '" + dir + "/m.bt'";
#endif
  // OctoMap's occupancy rule on both maps (the .bt keeps only free/occupied).
  r = cli(dir, "eval '" + dir + "/m.fgm' --scene '" + kCampusObj + "'" + octomap +
                   " --octomap-threshold --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  const nlohmann::json& m = j["map"];
  EXPECT_GT(m["occupied"].get<int64_t>(), 500);
  EXPECT_GT(m["precision"].get<double>(), 0.98);  // 2 cm range noise at 5 cm voxels
  EXPECT_GT(m["recall"].get<double>(), 0.0);
  EXPECT_LT(m["free_error"].get<double>(), 0.01);
  EXPECT_LE(m["free_inside_deep"].get<int64_t>(), m["free_inside"].get<int64_t>());
#ifdef FRAGG_CLI_HAS_OCTOMAP
  const nlohmann::json& o = j["octomap"];
  EXPECT_GT(o["occupied"].get<int64_t>(), 500);
  // Same scans, sensor model and rule: the same quality, up to rays that graze cell edges.
  auto near = [&](const char* key, double rel) {
    const double a = m[key].get<double>(), b = o[key].get<double>();
    EXPECT_NEAR(a, b, rel * b) << key;
  };
  near("precision", 1e-3);
  near("recall", 1e-2);
  near("free_error", 2e-2);
#endif
  // The text report names both figures.
  r = cli(dir, "eval '" + dir + "/m.fgm' --scene '" + kScenes + "/campus.json'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("precision"), std::string::npos);
  EXPECT_NE(r.out.find("free error"), std::string::npos);
  // ... and says what each measures (issue 38: a bare "recall 6.8 %" read as a failure).
  EXPECT_NE(r.out.find("share of the surface voxels in the observed region that are occupied"),
            std::string::npos)
      << r.out;
}

TEST(CliEval, BadArgumentsAndInputs) {
  const std::string dir = test::testDir();
  auto r = cli(dir, "eval '" + dir + "/none.fgm' --scene '" + kCampusObj + "'");
  EXPECT_EQ(r.exit_code, 1) << r.err;  // missing map
  r = cli(dir, "eval '" + dir + "/none.fgm' --scene '" + dir + "/scene.txt'");
  EXPECT_EQ(r.exit_code, 2) << r.err;  // not an OBJ or a scene file
  EXPECT_NE(r.err.find("--scene"), std::string::npos) << r.err;
  r = cli(dir, "eval '" + dir + "/none.fgm'");
  EXPECT_EQ(r.exit_code, 2) << r.err;  // --scene is required
}

TEST(CliSim, RecordsAndRefusesUnknownTrajectoriesAndSensors) {
  const std::string dir = test::testDir();
  auto r = test::run(FRAGG_SIM_PATH, dir,
                     "record '" + kScenes +
                         "/pipes.json' --trajectory survey --sensor depth "
                         "--width 32 --height 24 --frames 3 --depth-folder '" +
                         dir + "/d' --obj '" + dir + "/pipes.obj'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("3 frames of 768 points"), std::string::npos) << r.out;
  r = test::run(FRAGG_CLI_PATH, dir, "build '" + dir + "/d' -o '" + dir + "/d.fgm' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["scans"], 3);

  r = test::run(
      FRAGG_SIM_PATH, dir,
      "record '" + kScenes + "/campus.json' --trajectory nowhere --kitti '" + dir + "/k'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("street"), std::string::npos) << r.err;  // lists the ones it has
  r = test::run(FRAGG_SIM_PATH, dir,
                "record '" + kScenes +
                    "/campus.json' --trajectory street --sensor sonar --kitti '" + dir + "/k'");
  EXPECT_EQ(r.exit_code, 2);
  r = test::run(FRAGG_SIM_PATH, dir, "record '" + kScenes + "/campus.json' --trajectory street");
  EXPECT_EQ(r.exit_code, 2);  // nothing to write
  r = test::run(FRAGG_SIM_PATH, dir,
                "record '" + dir + "/missing.json' --trajectory street --kitti '" + dir + "/k'");
  EXPECT_EQ(r.exit_code, 1);
  r = test::run(FRAGG_SIM_PATH, dir, "recrod x.json");  // a typo: named, the commands listed
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err,
            "fragg_map_sim: error: unknown command 'recrod'; the commands are: scene, record, "
            "info (see --help)\n");
}

}  // namespace
}  // namespace fragg::sim
