// fragg_map_bench: the CPU backend and OctoMap on the same scans in one process.
//
// Prints a table (markdown) and, with --json FILE, the same figures as JSON: ms/scan median and
// p99, voxel visits per second, the speed ratio, bytes per known voxel, and cell agreement.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/synthetic_lidar.h"
#include "fragg_map/errors.h"
#include "fragg_map/io/dataset.h"
#include "fragg_map/io/point_file.h"
#include "fragg_map/io/pose_file.h"
#include "fragg_map/map.h"
#include "percentile.h"
#ifdef FRAGG_HAVE_OCTOMAP
#include <octomap/octomap.h>

#include "fragg_map/interop/compare.h"
#include "fragg_map/interop/octomap_io.h"
#endif

namespace fragg::bench {
namespace {

using tools::percentile;

using Clock = std::chrono::steady_clock;

struct Workload {
  std::string name;
  std::vector<Scan> scans;
  double resolution_m;
  double max_range_m;
};

struct Figures {
  std::vector<double> ms;  // per scan
  uint64_t visits = 0;
  double seconds = 0;
  size_t known = 0;
  size_t bytes = 0;
};

Figures runFragg(const Workload& w, size_t count, int repeats, int threads, Map* keep) {
  Figures f;
  MapParams p;
  p.resolution_m = w.resolution_m;
  p.occupancy.unknown_band = 0.0;  // OctoMap's rule, for the agreement figures
  p.threads = threads;
  p.backend = Backend::kCpu;
  for (int r = 0; r < repeats; ++r) {
    Map map(p);
    for (size_t i = 0; i < count; ++i) {
      const Scan& s = w.scans[i];
      const auto t0 = Clock::now();
      const InsertStats st =
          map.insert(s.cloud, s.T_map_sensor, SensorModel::autoFromCloud(0.0, w.max_range_m));
      const double sec = std::chrono::duration<double>(Clock::now() - t0).count();
      f.ms.push_back(sec * 1e3);
      f.seconds += sec;
      f.visits += st.voxel_visits;
    }
    if (r + 1 == repeats) {
      const MemoryStats m = map.memory();
      f.known = m.known_voxels;
      f.bytes = m.host_block_bytes;
      if (keep) *keep = std::move(map);
    }
  }
  return f;
}

#ifdef FRAGG_HAVE_OCTOMAP
struct OctomapRun {
  Figures figures;
  double both = 0, either = 0;
};

OctomapRun runOctomap(const Workload& w, size_t count, const Map& fragg_map) {
  OctomapRun out;
  octomap::OcTree tree(w.resolution_m);  // OctoMap's defaults = fragg's defaults
  for (size_t i = 0; i < count; ++i) {
    const Scan& s = w.scans[i];
    octomap::Pointcloud pc;
    pc.reserve(s.cloud.size());
    for (const auto& p : s.cloud.points_S) {
      if (!p.allFinite() || p.squaredNorm() == 0.f) continue;
      const Eigen::Vector3d q = s.T_map_sensor * p.cast<double>();
      pc.push_back(float(q.x()), float(q.y()), float(q.z()));
    }
    const Eigen::Vector3d o = s.T_map_sensor.translation();
    const auto t0 = Clock::now();
    tree.insertPointCloud(pc, octomap::point3d(o.x(), o.y(), o.z()), w.max_range_m);
    const double sec = std::chrono::duration<double>(Clock::now() - t0).count();
    out.figures.ms.push_back(sec * 1e3);
    out.figures.seconds += sec;
  }
  out.figures.bytes = tree.memoryUsage();
  // Agreement, cell by cell, with OctoMap's occupancy rule on both sides.
  const Map octo_map = fromOcTree(tree);
  CompareOptions rule;
  rule.octomap_threshold = true;
  const MapComparison c = compareMaps(fragg_map, octo_map, rule);
  out.figures.known = c.known_in_b;
  out.both = c.agreementInBoth();
  out.either = c.agreementInEither();
  return out;
}
#endif

std::vector<Scan> readAll(const std::string& input) {
  std::vector<Scan> scans;
  auto src = openDataset(input);
  Scan s;
  while (src->next(s)) scans.push_back(s);
  return scans;
}

Scan fileScan(const std::string& path, const Eigen::Isometry3d& T = Eigen::Isometry3d::Identity()) {
  Scan s;
  s.cloud = readPointFile(path);
  s.T_map_sensor = T;
  return s;
}

}  // namespace
}  // namespace fragg::bench

int main(int argc, char** argv) {
  using namespace fragg;
  using namespace fragg::bench;
  CLI::App app{"fragg_map_bench: fragg (CPU backend) against OctoMap on the same scans"};
  std::string data = "../shared/data/real", json_path, only;
  int synthetic_scans = 20, octomap_scans = 3, repeats = 3, threads = 0;
  double synthetic_res = 0.05;
  app.add_option("--data", data, "Real data folder (shared/data/real)")->capture_default_str();
  app.add_option("--synthetic-scans", synthetic_scans, "Synthetic 180k-point scans")
      ->capture_default_str();
  app.add_option("--octomap-scans", octomap_scans,
                 "Scans per workload given to OctoMap (it is slow); fragg figures for the ratio "
                 "use the same scans")
      ->capture_default_str();
  app.add_option("--repeats", repeats, "Repetitions of each fragg run")->capture_default_str();
  app.add_option("--threads", threads, "CPU threads for fragg (0 = every core)");
  app.add_option("--synthetic-resolution", synthetic_res, "Resolution of the synthetic runs")
      ->capture_default_str();
  app.add_option("--only", only, "Run only workloads whose name contains this");
  app.add_option("--json", json_path, "Write the figures as JSON to this file");
  CLI11_PARSE(app, argc, argv);

  try {
    std::vector<Workload> workloads;
    auto want = [&](const std::string& n) {
      return only.empty() || n.find(only) != std::string::npos;
    };
    const std::string d = data + "/";
    if (want("velodyne_pair")) {
      const Eigen::Isometry3d T = readMatrix4(d + "small_gicp_pair/T_target_source.txt");
      workloads.push_back({"velodyne_pair (HDL-32E, 2 scans)",
                           {fileScan(d + "small_gicp_pair/target.ply"),
                            fileScan(d + "small_gicp_pair/source.ply", T)},
                           0.05,
                           30.0});
    }
    if (want("room"))
      workloads.push_back({"room_scans (2 x 112k indoor)",
                           {fileScan(d + "pcl_room_scans/room_scan1.pcd"),
                            fileScan(d + "pcl_room_scans/room_scan2.pcd")},
                           0.05,
                           -1.0});
    if (want("vls128"))
      workloads.push_back({"vls128 (208k, outdoor)",
                           {fileScan(d + "nebula_single_scans/vls128_1585897255376374245.pcd")},
                           0.05,
                           30.0});
    if (want("rgbd"))
      workloads.push_back(
          {"rgbd (5 x 640x480 Kinect)", readAll(d + "slambook2_ch5_rgbd"), 0.05, -1.0});
    for (double range : {30.0, 50.0}) {
      const std::string name = fmt::format("synthetic lidar360 (180k pts, {:.0f} m)", range);
      if (!want(name) || synthetic_scans <= 0) continue;
      SyntheticLidarOptions so;
      SyntheticLidar sim(so);
      Workload w{name, {}, synthetic_res, range};
      for (int i = 0; i < synthetic_scans; ++i) w.scans.push_back(sim.scan(i));
      workloads.push_back(std::move(w));
    }

    nlohmann::json out = nlohmann::json::array();
    std::printf(
        "| workload | res m | scans | pts/scan | fragg ms/scan median | p99 | "
        "visits/s | OctoMap ms/scan median | speed-up | fragg B/voxel | OctoMap "
        "B/voxel | agree both | agree either |\n|---|---|---|---|---|---|---|---|---|---|"
        "---|---|---|\n");
    for (const Workload& w : workloads) {
      size_t points = 0;
      for (const Scan& s : w.scans) points += s.cloud.size();
      const size_t n_octo = std::min<size_t>(w.scans.size(), octomap_scans);
      Map fragg_same;
      const Figures all = runFragg(w, w.scans.size(), repeats, threads, nullptr);
      const Figures same = runFragg(w, n_octo, repeats, threads, &fragg_same);
      nlohmann::json j = {{"workload", w.name},
                          {"resolution_m", w.resolution_m},
                          {"max_range_m", w.max_range_m},
                          {"scans", w.scans.size()},
                          {"points_per_scan", points / w.scans.size()},
                          {"fragg_ms_median", percentile(all.ms, 0.5)},
                          {"fragg_ms_p99", percentile(all.ms, 0.99)},
                          {"fragg_visits_per_s", all.visits / all.seconds},
                          {"fragg_bytes_per_known_voxel", double(same.bytes) / same.known},
                          {"fragg_known_voxels", same.known}};
      std::string octo_cols = "| - | - | - | - | - |";
#ifdef FRAGG_HAVE_OCTOMAP
      const OctomapRun octo = runOctomap(w, n_octo, fragg_same);
      const double octo_median = percentile(octo.figures.ms, 0.5);
      const double speedup = octo_median / percentile(same.ms, 0.5);
      j["octomap_scans"] = n_octo;
      j["octomap_ms_median"] = octo_median;
      j["fragg_ms_median_same_scans"] = percentile(same.ms, 0.5);
      j["speedup"] = speedup;
      j["octomap_bytes_per_known_voxel"] = double(octo.figures.bytes) / octo.figures.known;
      j["octomap_known_voxels"] = octo.figures.known;
      j["agreement_both"] = octo.both;
      j["agreement_either"] = octo.either;
      octo_cols = fmt::format("| {:.1f} | {:.1f}x | {:.1f} | {:.1f} | {:.4f} % | {:.4f} % |",
                              octo_median, speedup, double(same.bytes) / same.known,
                              double(octo.figures.bytes) / octo.figures.known, 100 * octo.both,
                              100 * octo.either);
#endif
      std::printf("| %s | %.2f | %zu | %zu | %.2f | %.2f | %.3g %s\n", w.name.c_str(),
                  w.resolution_m, w.scans.size(), points / w.scans.size(), percentile(all.ms, 0.5),
                  percentile(all.ms, 0.99), all.visits / all.seconds, octo_cols.c_str());
      std::fflush(stdout);
      out.push_back(j);
    }
    if (!json_path.empty()) {
      std::ofstream f(json_path);
      f << out.dump(2) << "\n";
      if (!f) throw IoError("cannot write " + json_path);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fragg_map_bench: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
