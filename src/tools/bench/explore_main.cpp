// fragg_map_explore: closed-loop exploration in the simulator scenes (issue 14 item 6). From a
// start pose, frontiers -> clusters -> viewpoints -> move -> scan, step after step, with the
// gain-per-metre strategy and the nearest-frontier baseline; the explored volume against the
// scene's ground truth per step (bench/explore/explored_volume.h), as CSV and a JSON summary.
//
//   fragg_map_explore --scenario pipes|campus [--strategy gain|nearest|both] [--steps 30]
//       [--max-path M] [--resolution R] [--min-gain BITS] [--start X Y Z] [--start-yaw RAD]
//       [--backend cpu|cuda|auto] [--threads N] [--scenes DIR] [--csv FILE] [--json FILE]
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/explore/explored_volume.h"
#include "bench/explore/explorer.h"
#include "bench/explore/scenario.h"
#include "fragg_map/errors.h"
#include "fragg_map/geometry/mesh_bvh.h"

namespace fragg::explore {
namespace {

struct Options {
  std::string scenario, strategy = "both", scenes_dir = FRAGG_SCENES_DIR, backend = "cpu";
  std::string csv_path, json_path;
  int steps = 30, threads = 0;
  bool verbose = false;
  double max_path_m = 0.0, resolution_m = 0.0, min_gain_bits = 1.0;
  std::vector<double> start;
  double start_yaw_rad = std::numeric_limits<double>::quiet_NaN();
};

/// Steps and path length at which a run first reached `fraction` (null when it did not).
nlohmann::json firstReaching(const ExploreRun& r, double fraction) {
  for (const StepRecord& s : r.steps)
    if (s.explored >= fraction) return {{"step", s.step}, {"path_m", s.path_m}};
  return nullptr;
}

nlohmann::json summary(const ExploreRun& r) {
  double sums[6] = {0, 0, 0, 0, 0, 0};
  size_t moves = 0;
  for (const StepRecord& s : r.steps) {
    sums[4] += s.simulate_ms;
    sums[5] += s.insert_ms;
    if (s.step == 0) continue;
    ++moves;
    sums[0] += s.frontier_ms;
    sums[1] += s.cluster_ms;
    sums[2] += s.gain_ms;
    sums[3] += s.path_ms;
  }
  const StepRecord& last = r.steps.back();
  const double m = moves ? double(moves) : 1.0, n = double(r.steps.size());
  return {{"scenario", r.scenario},
          {"strategy", toString(r.strategy)},
          {"backend", r.backend},
          {"moves", moves},
          {"stop_reason", r.stop_reason},
          {"path_m", last.path_m},
          {"explored", last.explored},
          {"known_m3", double(last.known_cells) * r.cell_m3},
          {"reference_cells", r.reference_cells},
          {"reference_m3", double(r.reference_cells) * r.cell_m3},
          {"reached_50", firstReaching(r, 0.5)},
          {"reached_75", firstReaching(r, 0.75)},
          {"reached_90", firstReaching(r, 0.9)},
          {"mean_ms_per_move",
           {{"frontiers", sums[0] / m},
            {"clusters", sums[1] / m},
            {"gains", sums[2] / m},
            {"path_checks", sums[3] / m}}},
          {"mean_ms_per_scan", {{"simulate", sums[4] / n}, {"insert", sums[5] / n}}}};
}

int run(const Options& o) {
  Scenario s;
  if (o.scenario == "pipes") {
    s = pipesScenario(o.scenes_dir);
  } else if (o.scenario == "campus") {
    s = campusScenario(o.scenes_dir);
  } else {
    throw InvalidArgument("--scenario must be pipes or campus, not '" + o.scenario + "'");
  }
  std::vector<Strategy> strategies;
  if (o.strategy == "both") {
    strategies = {Strategy::kGainPerMetre, Strategy::kNearestFrontier};
  } else {
    strategies = {strategyFromString(o.strategy)};
  }
  if (o.resolution_m != 0.0) s.resolution_m = o.resolution_m;
  if (!o.start.empty()) {
    if (o.start.size() != 3) throw InvalidArgument("--start takes three numbers: x y z");
    s.start_m = Eigen::Vector3d(o.start[0], o.start[1], o.start[2]);
  }
  if (!std::isnan(o.start_yaw_rad)) s.start_yaw_rad = o.start_yaw_rad;
  ExploreLimits limits;
  limits.max_steps = o.steps;
  limits.max_path_m = o.max_path_m;
  limits.min_gain_bits = o.min_gain_bits;
  limits.backend = backendFromString(o.backend);
  limits.threads = o.threads;
  s.validate();
  limits.validate();

  const auto t0 = std::chrono::steady_clock::now();
  const geometry::MeshBvh bvh(s.scene.mesh);
  const ExploredVolume truth(bvh, s.box_min_m, s.box_max_m, s.resolution_m, o.threads);
  const double truth_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf(
      "%s\n",
      fmt::format("{}: {} cm cells, box [{:.1f} {:.1f} {:.1f}]..[{:.1f} {:.1f} "
                  "{:.1f}] m, {} reference cells ({:.0f} m^3) of {} ({:.1f} s)",
                  s.name, s.resolution_m * 100, s.box_min_m.x(), s.box_min_m.y(), s.box_min_m.z(),
                  s.box_max_m.x(), s.box_max_m.y(), s.box_max_m.z(), truth.referenceCells(),
                  double(truth.referenceCells()) * truth.cellVolume_m3(), truth.boxCells(), truth_s)
          .c_str());
  std::fflush(stdout);
  std::vector<ExploreRun> runs;
  nlohmann::json j = {{"scenario", s.name},
                      {"resolution_m", s.resolution_m},
                      {"box_min_m", {s.box_min_m.x(), s.box_min_m.y(), s.box_min_m.z()}},
                      {"box_max_m", {s.box_max_m.x(), s.box_max_m.y(), s.box_max_m.z()}},
                      {"start_m", {s.start_m.x(), s.start_m.y(), s.start_m.z()}},
                      {"max_steps", o.steps},
                      {"max_path_m", o.max_path_m},
                      {"runs", nlohmann::json::array()}};
  for (Strategy st : strategies) {
    const auto t1 = std::chrono::steady_clock::now();
    auto progress = [&](const StepRecord& r) {
      if (!o.verbose) return;
      std::fprintf(stderr, "%s\n",
                   fmt::format("  {} step {:3d}: explored {:6.2f} %, path {:7.1f} m, frontiers "
                               "{:.0f} ms, clusters {:.0f} ms, gains {:.0f} ms",
                               toString(st), r.step, 100.0 * r.explored, r.path_m, r.frontier_ms,
                               r.cluster_ms, r.gain_ms)
                       .c_str());
    };
    runs.push_back(explore(s, bvh, truth, st, limits, progress));
    const double wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
    nlohmann::json sj = summary(runs.back());
    sj["wall_s"] = wall_s;
    const ExploreRun& r = runs.back();
    std::printf("%s\n", fmt::format("  {:8s} {:3d} moves, {:7.1f} m, explored {:6.2f} % "
                                    "({:.0f} m^3), stop: {}, {:.1f} s",
                                    toString(st), int(r.steps.size()) - 1, r.steps.back().path_m,
                                    100.0 * r.steps.back().explored, sj["known_m3"].get<double>(),
                                    r.stop_reason, wall_s)
                            .c_str());
    std::fflush(stdout);
    j["runs"].push_back(sj);
  }
  if (!o.csv_path.empty()) {
    std::ofstream f(o.csv_path);
    if (!(f << toCsv(runs, true))) throw IoError("cannot write " + o.csv_path);
  }
  if (!o.json_path.empty()) {
    std::ofstream f(o.json_path);
    if (!(f << j.dump(2) << "\n")) throw IoError("cannot write " + o.json_path);
  }
  return 0;
}

}  // namespace
}  // namespace fragg::explore

int main(int argc, char** argv) {
  fragg::explore::Options o;
  CLI::App app{"Closed-loop exploration benchmark: gain per metre against nearest frontier"};
  app.add_option("--scenario", o.scenario, "pipes (depth camera) | campus (LiDAR)")->required();
  app.add_option("--strategy", o.strategy, "gain | nearest | both")->capture_default_str();
  app.add_option("--steps", o.steps, "Moves after the first scan")->capture_default_str();
  app.add_option("--max-path", o.max_path_m, "Path length budget (m, 0 = none)")
      ->capture_default_str();
  app.add_option("--resolution", o.resolution_m, "Voxel edge (m; default: the scenario's)");
  app.add_option("--min-gain", o.min_gain_bits, "Viewpoints with less gain (bits) do not count")
      ->capture_default_str();
  app.add_option("--start", o.start, "Start position x y z (m)")->expected(3);
  app.add_option("--start-yaw", o.start_yaw_rad, "Start yaw (rad)");
  app.add_option("--backend", o.backend, "Map integration: cpu | cuda | auto")
      ->capture_default_str();
  app.add_option("--threads", o.threads, "CPU threads (0 = every core)")->capture_default_str();
  app.add_option("--scenes", o.scenes_dir, "Folder of the scene files")->capture_default_str();
  app.add_option("--csv", o.csv_path, "Per-step CSV");
  app.add_option("--json", o.json_path, "JSON summary");
  app.add_flag("--verbose,-v", o.verbose, "One line per step on stderr");
  try {
    app.parse(argc, argv);
    return fragg::explore::run(o);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fragg_map_explore: error: %s\n", e.what());
    return 1;
  }
}
