// fragg_map_frontier_bench: the frontier figures of issue 14 on W1 (scripts/make_workloads.sh).
// The map is built scan by scan; after each scan the incremental frontier tracker is updated
// (timed); then on the final map: a full recompute, clustering, and the gain of N candidate
// viewpoints (pinhole 64 x 48 rays, 10 m) on free cells around the clusters.
//
//   fragg_map_frontier_bench --workloads DIR [--max-scans 100] [--resolution 0.05]
//       [--max-range 30] [--backend cpu|cuda|auto] [--viewpoints 1000] [--json FILE]
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/workloads.h"
#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "fragg_map/planning/frontier_cells.h"
#include "fragg_map/planning/frontier_clusters.h"
#include "fragg_map/planning/frontier_tracker.h"
#include "fragg_map/planning/viewpoints.h"
#include "percentile.h"

namespace fragg::bench {
namespace {

using tools::percentile;
using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

struct Options {
  std::string workloads, backend = "auto", json_path;
  size_t max_scans = 100, viewpoints = 1000;
  double resolution_m = 0.05, max_range_m = 30.0;
  int threads = 0;
};

int run(const Options& o) {
  const auto loads = simWorkloads(o.workloads, o.max_scans,
                                  [](const std::string& n) { return n == "W1 lidar360 30 m"; });
  if (loads.empty()) throw IoError("no W1 workload in " + o.workloads);
  const Workload& w = loads.front();
  MapParams params;
  params.resolution_m = o.resolution_m;
  params.backend = backendFromString(o.backend);
  params.threads = o.threads;
  Map map(params);
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, o.max_range_m);
  planning::FrontierTracker tracker({}, o.threads);
  std::vector<double> insert_ms, update_ms, examined, changed;
  bool states_on_device = false;
  for (const Scan& s : w.scans) {
    auto t0 = Clock::now();
    map.insert(s.cloud, s.T_map_sensor, sensor);
    insert_ms.push_back(msSince(t0));
    const planning::FrontierUpdateStats st = tracker.update(map);
    if (!st.full) {
      update_ms.push_back(st.seconds * 1e3);
      examined.push_back(double(st.blocks_examined));
      changed.push_back(double(st.blocks_changed));
      states_on_device = st.states_on_device;
    }
  }
  std::vector<double> full_ms;
  std::vector<VoxelKey> full;
  for (int i = 0; i < 3; ++i) {
    const auto t0 = Clock::now();
    full = planning::findFrontierCells(map, {}, o.threads);
    full_ms.push_back(msSince(t0));
  }
  const bool equal = full == tracker.cells();
  auto t0 = Clock::now();
  planning::FrontierClusterer clusterer;
  const auto clusters = clusterer.cluster(map, full);
  const double cluster_ms = msSince(t0);

  // Candidates: free cells on rings around the clusters, facing them, round robin.
  std::vector<Eigen::Vector3d> positions;
  std::vector<double> yaws;
  const BlockView view = map.blockView();
  for (int ring = 1; ring <= 40 && positions.size() < o.viewpoints; ++ring)
    for (const auto& c : clusters) {
      if (positions.size() >= o.viewpoints) break;
      const double phi = 0.61803398875 * 2 * 3.14159265358979 * ring;
      const Eigen::Vector3d p =
          c.centroid_m + (0.5 + 0.1 * ring) * Eigen::Vector3d(std::cos(phi), std::sin(phi), 0);
      const Cell* cell = view.findCell(map.keyOf(p));
      if (!cell || map.state(*cell) != CellState::kFree) continue;
      positions.push_back(p);
      yaws.push_back(std::atan2(c.centroid_m.y() - p.y(), c.centroid_m.x() - p.x()));
    }
  planning::GainSensor camera;  // pinhole 64 x 48, 90 x 68.8 degrees, 10 m
  t0 = Clock::now();
  const std::vector<double> gains =
      planning::viewpointGainsBits(map, positions, yaws, camera, o.threads, Backend::kAuto);
  const double gain_ms = msSince(t0);
  double gain_sum = 0.0;
  for (double g : gains) gain_sum += g;

  std::printf("%s\n", fmt::format("W1 {} scans at {} m, {} m range, backend {}: {} blocks, {} "
                                  "frontier cells, {} clusters",
                                  w.scans.size(), o.resolution_m, o.max_range_m, map.backendName(),
                                  map.blockCount(), full.size(), clusters.size())
                          .c_str());
  std::printf("%s\n", fmt::format("insert            median {:8.2f} ms  p95 {:8.2f} ms",
                                  percentile(insert_ms, 0.5), percentile(insert_ms, 0.95))
                          .c_str());
  std::printf("%s\n", fmt::format("incremental update median {:7.2f} ms  p95 {:8.2f} ms  max "
                                  "{:8.2f} ms  ({:.0f} changed blocks read, {:.0f} examined, "
                                  "median; cell states read on the {})",
                                  percentile(update_ms, 0.5), percentile(update_ms, 0.95),
                                  percentile(update_ms, 1.0), percentile(changed, 0.5),
                                  percentile(examined, 0.5), states_on_device ? "device" : "host")
                          .c_str());
  std::printf("%s\n", fmt::format("full recompute    median {:8.2f} ms  (incremental set {} the "
                                  "full one)",
                                  percentile(full_ms, 0.5), equal ? "equals" : "DIFFERS FROM")
                          .c_str());
  std::printf("%s\n", fmt::format("clustering        {:8.2f} ms", cluster_ms).c_str());
  std::printf("%s\n", fmt::format("gain of {} viewpoints (pinhole {} x {}, {} m): {:.2f} ms, "
                                  "mean {:.0f} bits",
                                  positions.size(), camera.columns, camera.rows, camera.max_range_m,
                                  gain_ms, positions.empty() ? 0.0 : gain_sum / positions.size())
                          .c_str());
  if (!o.json_path.empty()) {
    const nlohmann::json j = {{"scans", w.scans.size()},
                              {"resolution_m", o.resolution_m},
                              {"backend", map.backendName()},
                              {"blocks", map.blockCount()},
                              {"frontier_cells", full.size()},
                              {"clusters", clusters.size()},
                              {"insert_ms_median", percentile(insert_ms, 0.5)},
                              {"update_ms_median", percentile(update_ms, 0.5)},
                              {"update_ms_p95", percentile(update_ms, 0.95)},
                              {"blocks_changed_median", percentile(changed, 0.5)},
                              {"blocks_examined_median", percentile(examined, 0.5)},
                              {"states_on_device", states_on_device},
                              {"full_ms_median", percentile(full_ms, 0.5)},
                              {"incremental_equals_full", equal},
                              {"cluster_ms", cluster_ms},
                              {"viewpoints", positions.size()},
                              {"gain_ms", gain_ms}};
    std::ofstream(o.json_path) << j.dump(2) << "\n";
  }
  return equal ? 0 : 1;
}

}  // namespace
}  // namespace fragg::bench

int main(int argc, char** argv) {
  fragg::bench::Options o;
  CLI::App app{"Frontier benchmark on W1: incremental updates, full recompute, viewpoint gains"};
  app.add_option("--workloads", o.workloads, "Folder of scripts/make_workloads.sh")->required();
  app.add_option("--max-scans", o.max_scans, "W1 scans to use")->capture_default_str();
  app.add_option("--resolution", o.resolution_m, "Voxel edge (m)")->capture_default_str();
  app.add_option("--max-range", o.max_range_m, "Max range (m)")->capture_default_str();
  app.add_option("--backend", o.backend, "auto | cpu | cuda (map integration)")
      ->capture_default_str();
  app.add_option("--viewpoints", o.viewpoints, "Candidate viewpoints to score")
      ->capture_default_str();
  app.add_option("--threads", o.threads, "CPU threads (0 = every core)")->capture_default_str();
  app.add_option("--json", o.json_path, "Write the figures as JSON");
  try {
    app.parse(argc, argv);
    return fragg::bench::run(o);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fragg_map_frontier_bench: error: %s\n", e.what());
    return 1;
  }
}
