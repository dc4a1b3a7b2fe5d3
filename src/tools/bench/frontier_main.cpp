// fragg_map_frontier_bench: the frontier figures of issue 14 on W1 (scripts/make_workloads.sh).
// The map is built scan by scan; after each scan the incremental frontier tracker is updated
// (timed); then on the final map: a full recompute, clustering, and the gain of N candidate
// viewpoints (pinhole 64 x 48 rays, 10 m) on free cells around the clusters. Wall and process
// CPU times are printed (CPU time is the steadier figure on a shared machine). With --map the
// final map is a saved one (no incremental part).
//
//   fragg_map_frontier_bench (--workloads DIR | --map MAP.fgm) [--max-scans 100]
//       [--resolution 0.05] [--max-range 30] [--backend cpu|cuda|auto] [--viewpoints 1000]
//       [--threads N] [--json FILE] [--lidar-query K --box X0 Y0 Z0 X1 Y1 Z1]
//       [--gain-kernel plain|sized|pooled|queued|pooled-queued|deferred|pooled-deferred|all]
//       [--gain-repeats 5]
//       [--gain-pool-blocks N] [--gain-refill-lanes 4]
// --gain-kernel picks the CUDA gain kernel (planning::GainKernel); `all` times the plain kernel
// as usual, then every kernel alternated in this process, --gain-repeats rounds, each kernel's
// gains compared with the plain kernel's.
// --lidar-query K times only the node's ~get_frontiers on a LiDAR map (a coarse grid of K cells,
// the coverage gain, k = 8) for the whole map and for the box, step by step.
#include <fmt/format.h>
#include <sys/resource.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/workloads.h"
#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "fragg_map/planning/coarse_map.h"
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
  std::string workloads, backend = "auto", json_path, map_path;
  size_t max_scans = 100, viewpoints = 1000;
  double resolution_m = 0.05, max_range_m = 30.0;
  int threads = 0;
  int coarse_cells = 0;               ///< > 0: also time the node's LiDAR query on this grid
  bool device_tracker = true;         ///< FrontierTracker::useDevice
  std::vector<double> box;            ///< its box (6 values), else around the map's centre
  std::string gain_kernel = "plain";  ///< a GainKernel's name, or "all"
  int gain_repeats = 5;               ///< rounds of the alternated kernels (`all`)
  size_t gain_pool_blocks = 0;        ///< GainDeviceOptions::pool_blocks
  int gain_refill_lanes = 4;          ///< GainDeviceOptions::refill_lanes
};

/// The gain kernels alternated in one process (--gain-kernel all): per round every kernel once
/// (wall time of viewpointGainsBits), then per kernel the median, its stages and pool counts
/// (one more call, stages timed apart) and its gains against the plain kernel's.
void compareGainKernels(const Map& map, const std::vector<Eigen::Vector3d>& positions,
                        const std::vector<double>& yaws, const planning::GainSensor& camera,
                        const Options& o) {
  const auto options = [&](planning::GainKernel k) {
    planning::GainDeviceOptions d;
    d.kernel = k;
    d.pool_blocks = o.gain_pool_blocks;
    d.refill_lanes = o.gain_refill_lanes;
    return d;
  };
  std::vector<std::vector<double>> gains;
  for (const planning::GainKernel k : planning::kGainKernels)  // warm-up: buffers allocated
    gains.push_back(planning::viewpointGainsBits(map, positions, yaws, camera, o.threads,
                                                 Backend::kAuto, options(k)));
  const size_t n_kernels = gains.size();
  std::vector<std::vector<double>> ms(n_kernels);
  for (int round = 0; round < o.gain_repeats; ++round) {
    std::string line = fmt::format("gain kernels, round {}:", round + 1);
    for (size_t k = 0; k < n_kernels; ++k) {
      const auto t0 = Clock::now();
      (void)planning::viewpointGainsBits(map, positions, yaws, camera, o.threads, Backend::kAuto,
                                         options(planning::kGainKernels[k]));
      ms[k].push_back(msSince(t0));
      line += fmt::format(" {} {:.2f} ms{}", planning::gainKernelName(planning::kGainKernels[k]),
                          ms[k].back(), k + 1 < n_kernels ? "," : "");
    }
    std::printf("%s\n", line.c_str());
  }
  for (size_t k = 0; k < n_kernels; ++k) {
    planning::GainTimings t;
    (void)planning::viewpointGainsBits(map, positions, yaws, camera, o.threads, Backend::kAuto,
                                       options(planning::kGainKernels[k]), &t);
    double max_rel = 0.0;
    for (size_t i = 0; i < positions.size(); ++i)
      max_rel = std::max(
          max_rel, std::abs(gains[k][i] - gains[0][i]) / std::max(1.0, std::abs(gains[0][i])));
    std::printf(
        "%s\n",
        fmt::format("gain kernel {:>13}: median {:.2f} ms (min {:.2f}, max {:.2f}, {} rounds); "
                    "stages: view {:.2f} ms, tables {:.2f} ms, walk {:.2f} ms in {} launches; "
                    "pool: {} blocks wanted, {} viewpoints rerun; gains {} the plain kernel's "
                    "(max relative difference {:.1e})",
                    planning::gainKernelName(planning::kGainKernels[k]),
                    ms[k].empty() ? 0.0 : percentile(ms[k], 0.5),
                    ms[k].empty() ? 0.0 : percentile(ms[k], 0.0),
                    ms[k].empty() ? 0.0 : percentile(ms[k], 1.0), ms[k].size(),
                    t.view_seconds * 1e3, t.tables_seconds * 1e3, t.walk_seconds * 1e3, t.rounds,
                    t.pool_blocks_wanted, t.pool_reruns,
                    max_rel <= 1e-9 ? "EQUAL TO" : "DIFFER FROM", max_rel)
            .c_str());
  }
}

/// Process CPU time (user + system), ms: with other work on the machine, the steadier figure.
double cpuMs() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return (u.ru_utime.tv_sec + u.ru_stime.tv_sec) * 1e3 +
         (u.ru_utime.tv_usec + u.ru_stime.tv_usec) * 1e-3;
}

/// The node's ~get_frontiers on a LiDAR map (its defaults: a coarse grid, the coverage gain,
/// k = 8), for the whole map and for a box: each step's median wall and CPU time of 3 runs.
void lidarQuery(const Map& map, const Options& o) {
  planning::ViewpointOptions views;
  views.gain = planning::ViewpointGain::kCoverage;
  views.top_k = 8;
  for (const bool in_box : {false, true}) {
    planning::FrontierFilter filter;
    if (in_box) {
      filter.use_box = true;
      filter.box_min_m = Eigen::Vector3d(o.box[0], o.box[1], o.box[2]);
      filter.box_max_m = Eigen::Vector3d(o.box[3], o.box[4], o.box[5]);
    }
    std::vector<double> wall[4], cpu[4];
    size_t cells = 0, clusters = 0, with_views = 0;
    for (int run = 0; run < 3; ++run) {
      auto t0 = Clock::now();
      double c0 = cpuMs();
      const Map coarse =
          in_box ? planning::coarseStateMapIn(map, o.coarse_cells, filter.box_min_m,
                                              filter.box_max_m, planning::viewpointReachM(views))
                 : planning::coarseStateMap(map, o.coarse_cells);
      const auto lap = [&](int step) {
        wall[step].push_back(msSince(t0));
        cpu[step].push_back(cpuMs() - c0);
        t0 = Clock::now();
        c0 = cpuMs();
      };
      lap(0);
      const auto listed = planning::findFrontierCells(coarse, filter, o.threads);
      lap(1);
      const auto found = planning::FrontierClusterer().cluster(coarse, listed);
      lap(2);
      const auto best = planning::clustersViewpoints(coarse, found, views, o.threads);
      lap(3);
      cells = listed.size(), clusters = found.size(), with_views = 0;
      for (const auto& v : best) with_views += v.empty() ? 0 : 1;
    }
    double total_wall = 0.0, total_cpu = 0.0;
    for (int step = 0; step < 4; ++step) {
      total_wall += percentile(wall[step], 0.5);
      total_cpu += percentile(cpu[step], 0.5);
    }
    std::printf(
        "%s\n",
        fmt::format("LiDAR query, {} (coarse cells of {}, coverage gain, k 8): {} frontier cells, "
                    "{} clusters ({} with viewpoints); medians of 3, wall / CPU ms: coarse copy "
                    "{:.1f} / {:.1f}, cells {:.1f} / {:.1f}, clusters {:.1f} / {:.1f}, viewpoints "
                    "{:.1f} / {:.1f}; total {:.1f} / {:.1f}",
                    in_box ? fmt::format("box {} {} {} .. {} {} {} m", o.box[0], o.box[1], o.box[2],
                                         o.box[3], o.box[4], o.box[5])
                           : std::string("whole map"),
                    o.coarse_cells, cells, clusters, with_views, percentile(wall[0], 0.5),
                    percentile(cpu[0], 0.5), percentile(wall[1], 0.5), percentile(cpu[1], 0.5),
                    percentile(wall[2], 0.5), percentile(cpu[2], 0.5), percentile(wall[3], 0.5),
                    percentile(cpu[3], 0.5), total_wall, total_cpu)
            .c_str());
  }
}

int run(const Options& o) {
  std::vector<Workload> loads;
  if (o.map_path.empty()) {
    loads = simWorkloads(o.workloads, o.max_scans,
                         [](const std::string& n) { return n == "W1 lidar360 30 m"; });
    if (loads.empty()) throw IoError("no W1 workload in " + o.workloads);
  }
  MapParams params;
  params.resolution_m = o.resolution_m;
  params.backend = backendFromString(o.backend);
  params.threads = o.threads;
  Map map = o.map_path.empty() ? Map(params) : Map::load(o.map_path, params.backend);
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, o.max_range_m);
  planning::FrontierTracker tracker({}, o.threads);
  tracker.useDevice(o.device_tracker);
  std::vector<double> insert_ms, update_ms, examined, changed, states_ms, compare_ms, examine_ms;
  bool states_on_device = false;
  const std::vector<Scan> no_scans;
  const std::vector<Scan>& scans = loads.empty() ? no_scans : loads.front().scans;
  if (o.coarse_cells > 0) {  // the LiDAR query only
    lidarQuery(map, o);
    return 0;
  }
  if (scans.empty()) tracker.update(map);
  for (const Scan& s : scans) {
    auto t0 = Clock::now();
    map.insert(s.cloud, s.T_map_sensor, sensor);
    insert_ms.push_back(msSince(t0));
    const planning::FrontierUpdateStats st = tracker.update(map);
    if (!st.full) {
      update_ms.push_back(st.seconds * 1e3);
      examined.push_back(double(st.blocks_examined));
      changed.push_back(double(st.blocks_changed));
      states_ms.push_back(st.states_seconds * 1e3);
      compare_ms.push_back(st.compare_seconds * 1e3);
      examine_ms.push_back(st.examine_seconds * 1e3);
      states_on_device = st.states_on_device;
    }
  }
  std::vector<double> full_ms, full_cpu_ms;
  std::vector<VoxelKey> full;
  for (int i = 0; i < 3; ++i) {
    const auto t0 = Clock::now();
    const double c0 = cpuMs();
    planning::FrontierTracker fresh({}, o.threads);  // a full recompute, set as block masks
    fresh.useDevice(o.device_tracker);
    fresh.update(map);
    full_ms.push_back(msSince(t0));
    full_cpu_ms.push_back(cpuMs() - c0);
    if (i == 2) full = fresh.cells();
  }
  const bool equal = full == tracker.cells();
  auto t0 = Clock::now();
  double c0 = cpuMs();
  const std::vector<VoxelKey> listed = planning::findFrontierCells(map, {}, o.threads);
  const double list_ms = msSince(t0), list_cpu_ms = cpuMs() - c0;
  t0 = Clock::now();
  c0 = cpuMs();
  planning::FrontierClusterer clusterer;
  const auto clusters = clusterer.cluster(map, listed);
  const double cluster_ms = msSince(t0), cluster_cpu_ms = cpuMs() - c0;

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
  planning::GainDeviceOptions device_gains;
  device_gains.kernel = o.gain_kernel == "all" ? planning::GainKernel::kPlain
                                               : planning::gainKernelFromName(o.gain_kernel);
  device_gains.pool_blocks = o.gain_pool_blocks;
  device_gains.refill_lanes = o.gain_refill_lanes;
  // Once to warm up (the device table and bitmaps are allocated on the first call), then timed.
  planning::viewpointGainsBits(map, positions, yaws, camera, o.threads, Backend::kAuto,
                               device_gains);
  t0 = Clock::now();
  c0 = cpuMs();
  const std::vector<double> gains = planning::viewpointGainsBits(
      map, positions, yaws, camera, o.threads, Backend::kAuto, device_gains);
  const double gain_ms = msSince(t0), gain_cpu_ms = cpuMs() - c0;
  double gain_sum = 0.0;
  for (double g : gains) gain_sum += g;
  // Once more with the device's stages timed (a synchronisation between them).
  planning::GainTimings gt;
  (void)planning::viewpointGainsBits(map, positions, yaws, camera, o.threads, Backend::kAuto,
                                     device_gains, &gt);
  // The part of a call that does not grow with the viewpoints (the view, tables, copies): one
  // viewpoint, medians of 5.
  std::vector<double> one_ms;
  for (int i = 0; i < 5 && !positions.empty(); ++i) {
    t0 = Clock::now();
    (void)planning::viewpointGainsBits(map, {positions[0]}, {yaws[0]}, camera, o.threads,
                                       Backend::kAuto, device_gains);
    one_ms.push_back(msSince(t0));
  }

  std::printf("%s\n", fmt::format("{}: backend {}: {} blocks, {} frontier cells, {} clusters",
                                  o.map_path.empty()
                                      ? fmt::format("W1 {} scans at {} m, {} m range", scans.size(),
                                                    o.resolution_m, o.max_range_m)
                                      : o.map_path,
                                  map.backendName(), map.blockCount(), full.size(), clusters.size())
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
  std::printf("%s\n", fmt::format("  of which (medians): changed blocks' cell states {:.2f} ms, "
                                  "compare + neighbourhoods {:.2f} ms, examine {:.2f} ms",
                                  percentile(states_ms, 0.5), percentile(compare_ms, 0.5),
                                  percentile(examine_ms, 0.5))
                          .c_str());
  std::printf("%s\n", fmt::format("full recompute    median {:8.2f} ms, CPU time {:.2f} ms "
                                  "(incremental set {} the full one)",
                                  percentile(full_ms, 0.5), percentile(full_cpu_ms, 0.5),
                                  equal ? "equals" : "DIFFERS FROM")
                          .c_str());
  std::printf("%s\n", fmt::format("cells listed      {:8.2f} ms, CPU time {:.2f} ms "
                                  "(findFrontierCells: recompute + the list of keys)",
                                  list_ms, list_cpu_ms)
                          .c_str());
  std::printf("%s\n", fmt::format("clustering        {:8.2f} ms, CPU time {:.2f} ms", cluster_ms,
                                  cluster_cpu_ms)
                          .c_str());
  std::printf("%s\n", fmt::format("gain of {} viewpoints (pinhole {} x {}, {} m): {:.2f} ms, "
                                  "CPU time {:.2f} ms, mean {:.0f} bits (one viewpoint: {:.2f} ms)",
                                  positions.size(), camera.columns, camera.rows, camera.max_range_m,
                                  gain_ms, gain_cpu_ms,
                                  positions.empty() ? 0.0 : gain_sum / positions.size(),
                                  one_ms.empty() ? 0.0 : percentile(one_ms, 0.5))
                          .c_str());
  if (gt.on_device)
    std::printf("%s\n",
                fmt::format("  of which (stages timed apart, {} kernel): device view "
                            "{:.2f} ms, tables and bitmaps {:.2f} ms, walk {:.2f} ms in "
                            "{} rounds",
                            planning::gainKernelName(device_gains.kernel), gt.view_seconds * 1e3,
                            gt.tables_seconds * 1e3, gt.walk_seconds * 1e3, gt.rounds)
                    .c_str());
  if (o.gain_kernel == "all" && gt.on_device) compareGainKernels(map, positions, yaws, camera, o);
  if (!o.json_path.empty()) {
    const nlohmann::json j = {{"scans", scans.size()},
                              {"map", o.map_path},
                              {"full_cpu_ms_median", percentile(full_cpu_ms, 0.5)},
                              {"list_ms", list_ms},
                              {"cluster_cpu_ms", cluster_cpu_ms},
                              {"gain_cpu_ms", gain_cpu_ms},
                              {"gain_sum_bits", gain_sum},
                              {"resolution_m", o.resolution_m},
                              {"backend", map.backendName()},
                              {"blocks", map.blockCount()},
                              {"frontier_cells", full.size()},
                              {"clusters", clusters.size()},
                              {"insert_ms_median", percentile(insert_ms, 0.5)},
                              {"update_ms_median", percentile(update_ms, 0.5)},
                              {"update_ms_p95", percentile(update_ms, 0.95)},
                              {"blocks_changed_median", percentile(changed, 0.5)},
                              {"update_states_ms_median", percentile(states_ms, 0.5)},
                              {"update_compare_ms_median", percentile(compare_ms, 0.5)},
                              {"update_examine_ms_median", percentile(examine_ms, 0.5)},
                              {"blocks_examined_median", percentile(examined, 0.5)},
                              {"states_on_device", states_on_device},
                              {"full_ms_median", percentile(full_ms, 0.5)},
                              {"incremental_equals_full", equal},
                              {"cluster_ms", cluster_ms},
                              {"viewpoints", positions.size()},
                              {"gain_ms", gain_ms},
                              {"gain_kernel", planning::gainKernelName(device_gains.kernel)}};
    std::ofstream(o.json_path) << j.dump(2) << "\n";
  }
  return equal ? 0 : 1;
}

}  // namespace
}  // namespace fragg::bench

int main(int argc, char** argv) {
  fragg::bench::Options o;
  CLI::App app{"Frontier benchmark on W1: incremental updates, full recompute, viewpoint gains"};
  auto* workloads =
      app.add_option("--workloads", o.workloads, "Folder of scripts/make_workloads.sh");
  auto* map_file = app.add_option(
      "--map", o.map_path, "A saved map instead of W1 (no incremental part; its own resolution)");
  workloads->excludes(map_file);
  map_file->excludes(workloads);
  app.add_option("--max-scans", o.max_scans, "W1 scans to use")->capture_default_str();
  app.add_option("--resolution", o.resolution_m, "Voxel edge (m)")->capture_default_str();
  app.add_option("--max-range", o.max_range_m, "Max range (m)")->capture_default_str();
  app.add_option("--backend", o.backend, "auto | cpu | cuda (map integration)")
      ->capture_default_str();
  app.add_option("--viewpoints", o.viewpoints, "Candidate viewpoints to score")
      ->capture_default_str();
  app.add_option("--threads", o.threads, "CPU threads (0 = every core)")->capture_default_str();
  app.add_flag("--device-tracker,!--host-tracker", o.device_tracker,
               "the frontier tracker's update on a CUDA map's device (FrontierTracker::useDevice; "
               "the default), or on the host");
  app.add_option("--lidar-query", o.coarse_cells,
                 "Only time the node's LiDAR query (coarse grid of N cells, coverage, k 8) on "
                 "the whole map and in --box")
      ->check(CLI::IsMember({1, 2, 4, 8}));
  app.add_option("--box", o.box, "The LiDAR query's box X0 Y0 Z0 X1 Y1 Z1 (m)")->expected(6);
  app.add_option("--json", o.json_path, "Write the figures as JSON");
  app.add_option("--gain-kernel", o.gain_kernel,
                 "CUDA gain kernel: plain | sized | pooled | queued | pooled-queued | deferred | "
                 "pooled-deferred, or all "
                 "(every kernel alternated, after the plain kernel's figures)")
      ->capture_default_str();
  app.add_option("--gain-repeats", o.gain_repeats, "Rounds of the alternated kernels (all)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--gain-pool-blocks", o.gain_pool_blocks,
                 "Pooled kernels: block bitmaps in the pool (0 = from the bitmap budget)")
      ->capture_default_str();
  app.add_option("--gain-refill-lanes", o.gain_refill_lanes,
                 "Queued kernels: idle lanes of a warp before it takes new rays (1..32)")
      ->capture_default_str()
      ->check(CLI::Range(1, 32));
  try {
    app.parse(argc, argv);
    if (o.workloads.empty() && o.map_path.empty())
      throw fragg::InvalidArgument("give --workloads DIR or --map MAP.fgm");
    if (o.coarse_cells > 0 && o.box.size() != 6)
      throw fragg::InvalidArgument("--lidar-query needs --box X0 Y0 Z0 X1 Y1 Z1");
    if (o.gain_kernel != "all") (void)fragg::planning::gainKernelFromName(o.gain_kernel);
    return fragg::bench::run(o);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fragg_map_frontier_bench: error: %s\n", e.what());
    return 1;
  }
}
