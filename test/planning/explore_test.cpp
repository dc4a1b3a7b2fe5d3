// fragg_map_explore's loop (src/tools/bench/explore) in a small room: the explored volume grows
// with the steps, two runs give the same CSV, the chosen viewpoints are clear of the scene's
// solids, the reference cells match a brute-force classification, and bad arguments are refused
// (by the library and by the executable).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "bench/explore/explored_volume.h"
#include "bench/explore/explorer.h"
#include "bench/explore/scenario.h"
#include "fragg_map/errors.h"
#include "fragg_map/geometry/mesh_bvh.h"
#include "interop_test_util.h"

namespace fragg::explore {
namespace {

/// A closed 6 x 4 x 2.5 m room with a pillar, a crate and a pipe.
const char* kRoomJson = R"({
 "name": "room",
 "ground": {"extent": [-3.5, -2.5, 3.5, 2.5], "z": 0.0, "cell": 0.5, "thickness": 0.3},
 "objects": [
  {"type": "box", "min": [-3.3, -2.3, -0.3], "max": [-3, 2.3, 2.8]},
  {"type": "box", "min": [3, -2.3, -0.3], "max": [3.3, 2.3, 2.8]},
  {"type": "box", "min": [-3, -2.3, -0.3], "max": [3, -2, 2.8]},
  {"type": "box", "min": [-3, 2, -0.3], "max": [3, 2.3, 2.8]},
  {"type": "box", "min": [-3, -2, 2.5], "max": [3, 2, 2.8]},
  {"type": "cylinder", "from": [0.5, 0.3, 0], "to": [0.5, 0.3, 2.5], "radius": 0.4, "segments": 16},
  {"type": "box", "min": [1.6, -1.6, 0], "max": [2.4, -0.8, 0.9]},
  {"type": "pipe", "from": [-2.8, 1.4, 1.8], "to": [2.8, 1.4, 1.8], "radius": 0.12}
 ],
 "trajectories": {}
})";

Scenario roomScenario() {
  Scenario s;
  s.name = "room";
  s.scene = sim::sceneFromJson(kRoomJson);
  s.sensor = ExploreSensor::kDepthCamera;
  s.depth.width = 64;
  s.depth.height = 48;
  s.depth.hfov_deg = 70.0;
  s.depth.max_range_m = 6.0;
  s.depth.noise_m = 0.001;  // noise and dropout on: the seed must make them repeatable
  s.depth.dropout = 0.01;
  s.seed = 7;
  s.resolution_m = 0.1;
  s.integration_max_range_m = 6.0;
  s.start_m = Eigen::Vector3d(-2.0, -1.0, 1.2);
  s.start_yaw_rad = 0.3;
  s.box_min_m = Eigen::Vector3d(-3.0, -2.0, 0.0);
  s.box_max_m = Eigen::Vector3d(3.0, 2.0, 2.5);
  s.min_sensor_z_m = 0.6;
  s.max_sensor_z_m = 1.9;
  s.robot_radius_m = 0.15;
  s.clusters.min_cells = 10;
  s.clusters.max_extent_m = 1.5;
  s.viewpoints.radii_m = {0.8, 1.5};
  s.viewpoints.angles = 6;
  s.viewpoints.clearance_m = 0.3;
  s.viewpoints.sensor.columns = 16;
  s.viewpoints.sensor.rows = 12;
  s.viewpoints.sensor.horizontal_fov_rad = 70.0 * M_PI / 180.0;
  s.viewpoints.sensor.vertical_fov_rad = 0.967;
  s.viewpoints.sensor.max_range_m = 5.0;
  return s;
}

ExploreLimits fewSteps() {
  ExploreLimits l;
  l.max_steps = 6;
  l.threads = 2;
  return l;
}

TEST(ExploreTest, ReferenceCellsMatchBruteForce) {
  const Scenario s = roomScenario();
  const geometry::MeshBvh bvh(s.scene.mesh);
  const ExploredVolume truth(bvh, s.box_min_m, s.box_max_m, s.resolution_m, 2);
  // Cell centres 0.05 .. 2.95 etc.: 60 x 40 x 25 cells in the box.
  EXPECT_EQ(truth.boxCells(), 60u * 40u * 25u);
  uint64_t expected = 0;
  auto inside = [&](int x, int y, int z) {
    return bvh.inside(Eigen::Vector3f((x + 0.5f) * 0.1f, (y + 0.5f) * 0.1f, (z + 0.5f) * 0.1f));
  };
  for (int z = 0; z < 25; ++z)
    for (int y = -20; y < 20; ++y)
      for (int x = -30; x < 30; ++x) {
        bool ref = !inside(x, y, z);
        const int d[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
        for (const auto& o : d) {
          const int nx = x + o[0], ny = y + o[1], nz = z + o[2];
          if (nx < -30 || nx >= 30 || ny < -20 || ny >= 20 || nz < 0 || nz >= 25) continue;
          if (!ref && !inside(nx, ny, nz)) ref = true;
        }
        expected += ref;
      }
  EXPECT_EQ(truth.referenceCells(), expected);
  // The pillar, crate and pipe take volume out: fewer reference cells than box cells.
  EXPECT_LT(truth.referenceCells(), truth.boxCells());
  EXPECT_GT(truth.referenceCells(), truth.boxCells() * 8 / 10);
}

TEST(ExploreTest, ExploredVolumeGrowsAndViewpointsAreClear) {
  const Scenario s = roomScenario();
  const geometry::MeshBvh bvh(s.scene.mesh);
  const ExploredVolume truth(bvh, s.box_min_m, s.box_max_m, s.resolution_m, 2);
  for (Strategy st : {Strategy::kGainPerMetre, Strategy::kNearestFrontier}) {
    SCOPED_TRACE(toString(st));
    const ExploreRun run = explore(s, bvh, truth, st, fewSteps());
    ASSERT_GE(run.steps.size(), 4u) << "stopped early: " << run.stop_reason;
    EXPECT_EQ(run.steps.front().step, 0);
    EXPECT_EQ(run.steps.front().path_m, 0.0);
    EXPECT_GT(run.steps.front().explored, 0.0);
    for (size_t i = 1; i < run.steps.size(); ++i) {
      const StepRecord& a = run.steps[i - 1];
      const StepRecord& b = run.steps[i];
      // A scan can bring a few cells back into the unknown band (a free cell hit, an occupied
      // one crossed), never many.
      EXPECT_GE(double(b.known_cells), 0.99 * double(a.known_cells)) << "step " << b.step;
      EXPECT_NEAR(b.path_m - a.path_m, (b.position_m - a.position_m).norm(), 1e-9);
      EXPECT_GT(b.gain_bits, 0.0);
      EXPECT_GT(b.frontier_cells, 0u);
      EXPECT_GT(b.clusters, 0u);
      // Clear of every solid of the ground truth by at least the robot's radius.
      const Eigen::Vector3f p = b.position_m.cast<float>();
      EXPECT_FALSE(bvh.inside(p)) << "step " << b.step;
      EXPECT_GE(bvh.distance(p, 1.0f), s.robot_radius_m) << "step " << b.step;
      EXPECT_GE(b.position_m.z(), s.min_sensor_z_m - 1e-9);
      EXPECT_LE(b.position_m.z(), s.max_sensor_z_m + 1e-9);
    }
    EXPECT_GT(run.steps.back().explored, run.steps.front().explored + 0.1);
    EXPECT_GT(run.steps[run.steps.size() / 2].explored, run.steps.front().explored);
    EXPECT_LE(run.steps.back().explored, 1.0);
  }
}

TEST(ExploreTest, TwoRunsGiveTheSameCsv) {
  const Scenario s = roomScenario();
  const geometry::MeshBvh bvh(s.scene.mesh);
  const ExploredVolume truth(bvh, s.box_min_m, s.box_max_m, s.resolution_m, 2);
  ExploreLimits one = fewSteps();
  one.max_steps = 3;
  ExploreLimits other = one;
  other.threads = 1;  // the thread count must not change the choices either
  const std::vector<ExploreRun> a = {explore(s, bvh, truth, Strategy::kGainPerMetre, one)};
  const std::vector<ExploreRun> b = {explore(s, bvh, truth, Strategy::kGainPerMetre, other)};
  EXPECT_EQ(toCsv(a, false), toCsv(b, false));
  EXPECT_GE(a.front().steps.size(), 3u);
  // Every row has the header's columns; with times six more.
  auto columns = [](const std::string& csv) {
    std::vector<size_t> n;
    size_t start = 0;
    for (size_t end = csv.find('\n'); end != std::string::npos;
         start = end + 1, end = csv.find('\n', start))
      n.push_back(size_t(std::count(csv.begin() + start, csv.begin() + end, ',')) + 1);
    return n;
  };
  const std::vector<size_t> plain = columns(toCsv(a, false)), timed = columns(toCsv(a, true));
  ASSERT_EQ(plain.size(), a.front().steps.size() + 1);
  ASSERT_EQ(timed.size(), plain.size());
  for (size_t i = 0; i < plain.size(); ++i) {
    EXPECT_EQ(plain[i], plain[0]) << "line " << i;
    EXPECT_EQ(timed[i], plain[0] + 6) << "line " << i;
  }
}

TEST(ExploreTest, PathBudgetStopsTheRun) {
  const Scenario s = roomScenario();
  const geometry::MeshBvh bvh(s.scene.mesh);
  const ExploredVolume truth(bvh, s.box_min_m, s.box_max_m, s.resolution_m, 2);
  ExploreLimits l = fewSteps();
  l.max_steps = 4;
  const ExploreRun free_run = explore(s, bvh, truth, Strategy::kNearestFrontier, l);
  ASSERT_EQ(free_run.stop_reason, "step budget");
  const double total_m = free_run.steps.back().path_m;
  ASSERT_GT(total_m, 0.0);
  // A budget just below the free run's path: the same moves, all but the last.
  l.max_path_m = total_m - 1e-6;
  const ExploreRun run = explore(s, bvh, truth, Strategy::kNearestFrontier, l);
  EXPECT_EQ(run.stop_reason, "path budget");
  EXPECT_LE(run.steps.back().path_m, l.max_path_m);
  ASSERT_EQ(run.steps.size() + 1, free_run.steps.size());
  ExploreRun prefix = free_run;
  prefix.steps.pop_back();
  EXPECT_EQ(toCsv({run}, false), toCsv({prefix}, false));
}

TEST(ExploreTest, BadArgumentsAreRefused) {
  const Scenario good = roomScenario();
  const geometry::MeshBvh bvh(good.scene.mesh);
  const ExploredVolume truth(bvh, good.box_min_m, good.box_max_m, good.resolution_m, 2);
  auto refuses = [&](const Scenario& s, const ExploreLimits& l) {
    EXPECT_THROW(explore(s, bvh, truth, Strategy::kGainPerMetre, l), InvalidArgument);
  };
  ExploreLimits l = fewSteps();
  l.max_steps = 0;
  refuses(good, l);
  l = fewSteps();
  l.max_path_m = std::nan("");
  refuses(good, l);
  l = fewSteps();
  l.min_gain_bits = -1.0;
  refuses(good, l);
  l = fewSteps();
  l.threads = -1;
  refuses(good, l);
  Scenario s = good;
  s.start_m.x() = 10.0;  // outside the box
  refuses(s, fewSteps());
  s = good;
  s.resolution_m = std::nan("");
  refuses(s, fewSteps());
  s = good;
  s.box_max_m.z() = -1.0;
  refuses(s, fewSteps());
  s = good;
  s.viewpoints.top_k = 0;
  refuses(s, fewSteps());
  s = good;
  s.clusters.min_cells = 0;
  refuses(s, fewSteps());
  s = good;
  s.robot_radius_m = 0.0;
  refuses(s, fewSteps());
  s = good;
  s.depth.width = 0;
  refuses(s, fewSteps());
  EXPECT_THROW(strategyFromString("random"), InvalidArgument);
  EXPECT_THROW(ExploredVolume(bvh, good.box_max_m, good.box_min_m, 0.1), InvalidArgument);
  EXPECT_THROW(ExploredVolume(bvh, good.box_min_m, good.box_max_m, 0.0), InvalidArgument);
  // A map at another resolution cannot be measured against these reference cells.
  MapParams p;
  p.resolution_m = 0.2;
  EXPECT_THROW(truth.knownReferenceCells(Map(p)), InvalidArgument);
}

TEST(ExploreTest, ExecutableRefusesBadArguments) {
  const std::string dir = test::testDir();
  for (const std::string& args : std::vector<std::string>{
           "--scenario moon", "--scenario pipes --strategy random", "--scenario pipes --steps 0",
           "--scenario pipes --resolution nan", "--scenario pipes --start 100 0 1",
           "--scenario pipes --min-gain -3", "--scenario pipes --backend gpu2",
           "--scenario pipes --scenes '" + dir + "/missing'"}) {
    SCOPED_TRACE(args);
    const auto r = test::runCli(dir, args);
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.err.find("fragg_map_explore: error:"), std::string::npos) << r.err;
  }
  const auto r = test::runCli(dir, "--steps 3");  // --scenario is required
  EXPECT_NE(r.exit_code, 0);
}

}  // namespace
}  // namespace fragg::explore
