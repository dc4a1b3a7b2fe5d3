// fragg_map_loop_bench: the paper's Fig. 5a. A map is built from drifting poses with its scans
// kept; then the last k scans are moved to their true poses (Map::correctPoses) and the time
// is set against one insertion and against rebuilding the whole map with the true poses.
// Also: agreement of the corrected map (every scan corrected) with the rebuilt one.
//
//   fragg_map_loop_bench --kitti DIR [--odom DIR/poses_odom.txt] --backends cpu cuda
//       --ks 1 10 50 100 [--resolution 0.05] [--max-range 30] [--json F] [--save-maps PREFIX]
//
// Without --odom the drift is made up: scan i is moved by i x (--drift-m, --drift-rad).
#include <fmt/format.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/engines.h"
#include "fragg_map/errors.h"
#include "fragg_map/interop/compare.h"
#include "fragg_map/io/dataset.h"
#include "fragg_map/io/pose_file.h"
#include "fragg_map/map.h"
#include "percentile.h"

namespace fragg::bench {
namespace {

using tools::percentile;

struct Options {
  std::string kitti, odom, json_path, save_prefix;
  bool from_file = false;
  std::vector<std::string> backends = {"cpu"};
  std::vector<size_t> ks = {1, 10, 50, 100};
  double resolution_m = 0.05, max_range_m = 30.0;
  double drift_m = 0.01, drift_rad = 0.001;
  size_t max_scans = 0;
  int threads = 0;
};

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// The drifting poses the map is first built with.
std::vector<Eigen::Isometry3d> driftedPoses(const Options& o, const std::vector<Scan>& scans) {
  std::vector<Eigen::Isometry3d> out;
  if (!o.odom.empty()) {
    const auto odom = readKittiPoses(o.odom);
    const Eigen::Isometry3d Tr =
        readKittiCalibTr((std::filesystem::path(o.kitti) / "calib.txt").string());
    if (odom.size() < scans.size())
      throw InvalidArgument(o.odom + " has fewer poses than the sequence has scans");
    for (size_t i = 0; i < scans.size(); ++i) out.push_back(Tr.inverse() * odom[i] * Tr);
    return out;
  }
  for (size_t i = 0; i < scans.size(); ++i) {
    Eigen::Isometry3d drift = Eigen::Isometry3d::Identity();
    drift.translation() = Eigen::Vector3d(o.drift_m * i, 0.5 * o.drift_m * i, 0.0);
    drift.linear() =
        Eigen::AngleAxisd(o.drift_rad * i, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    out.push_back(scans[i].T_map_sensor * drift);
  }
  return out;
}

struct Built {
  Map map;
  std::vector<double> ms;
  double seconds = 0;
};

Built build(const std::vector<Scan>& scans, const std::vector<Eigen::Isometry3d>& poses,
            const MapParams& params, const SensorModel& sensor) {
  Built b{Map(params), {}, 0.0};
  const auto t0 = std::chrono::steady_clock::now();
  for (size_t i = 0; i < scans.size(); ++i)
    b.ms.push_back(b.map.insert(scans[i].cloud, poses[i], sensor, scans[i].stamp_ns).seconds_total *
                   1e3);
  b.seconds = secondsSince(t0);
  return b;
}

nlohmann::json runBackend(const std::string& engine, const Options& o,
                          const std::vector<Scan>& scans,
                          const std::vector<Eigen::Isometry3d>& drifted) {
  MapParams base;
  base.resolution_m = o.resolution_m;
  base.threads = o.threads;
  MapParams params = engineParams(engine, base);
  params.scans.keep = true;
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, o.max_range_m);
  std::vector<Eigen::Isometry3d> truth;
  for (const Scan& s : scans) truth.push_back(s.T_map_sensor);

  // The drifted map. Each k starts from a new one: built again in this process (the state of
  // a live system when the loop closes: recent blocks on the device), or with --from-file
  // loaded from a file saved once (every block on the host, nothing warm).
  Built drift = build(scans, drifted, params, sensor);
  const double insert_median = percentile(drift.ms, 0.5);
  const std::string tmp = (std::filesystem::temp_directory_path() /
                           ("fragg_loop_" + engine + "_" + std::to_string(::getpid()) + ".fgm"))
                              .string();
  if (o.from_file) drift.map.save(tmp);
  const std::string backend_name = drift.map.backendName();
  // Rebuild with the true poses: what a system without removal has to do.
  Built rebuilt = build(scans, truth, params, sensor);
  std::fprintf(stderr, "[loop] %s: built %zu scans (median %.2f ms/scan), rebuild %.1f ms\n",
               engine.c_str(), scans.size(), insert_median, rebuilt.seconds * 1e3);

  nlohmann::json rows = nlohmann::json::array();
  std::vector<size_t> ks = o.ks;
  if (std::find(ks.begin(), ks.end(), scans.size()) == ks.end()) ks.push_back(scans.size());
  double agreement = 0.0, before = 0.0;
  for (size_t k : ks) {
    if (k == 0 || k > scans.size()) continue;
    Map map =
        o.from_file ? Map::load(tmp, params.backend) : build(scans, drifted, params, sensor).map;
    std::map<ScanId, Eigen::Isometry3d> fix;
    for (size_t i = scans.size() - k; i < scans.size(); ++i) fix[ScanId(i)] = truth[i];
    const CorrectionStats st = map.correctPoses(fix);
    const double ms = st.seconds_total * 1e3;
    auto stages = [](const InsertStats& t) {
      return fmt::format(
          "cull {:.1f} prepare {:.1f} residency {:.1f} raycast {:.1f} apply {:.1f} "
          "total {:.1f}",
          t.seconds_cull * 1e3, t.seconds_prepare * 1e3, t.seconds_residency * 1e3,
          t.seconds_raycast * 1e3, t.seconds_apply * 1e3, t.seconds_total * 1e3);
    };
    std::fprintf(stderr, "[loop] %s k=%zu removal: %s | insertion: %s (ms)\n", engine.c_str(), k,
                 stages(st.removal).c_str(), stages(st.insertion).c_str());
    rows.push_back({{"k", k},
                    {"ms_total", ms},
                    {"ms_per_scan", ms / k},
                    {"ms_removal", st.removal.seconds_total * 1e3},
                    {"ms_insertion", st.insertion.seconds_total * 1e3},
                    {"per_scan_vs_insert", ms / k / insert_median},
                    {"speedup_vs_rebuild", rebuilt.seconds * 1e3 / ms}});
    std::printf("%s\n", fmt::format("| {} | {} | {:.1f} | {:.2f} | {:.2f}x | {:.1f} | {:.1f}x |",
                                    engine, k, ms, ms / k, ms / k / insert_median,
                                    rebuilt.seconds * 1e3, rebuilt.seconds * 1e3 / ms)
                            .c_str());
    if (k == scans.size()) {
      before = compareMaps(drift.map, rebuilt.map).agreementInEither();
      agreement = compareMaps(map, rebuilt.map).agreementInEither();
      if (!o.save_prefix.empty()) {
        drift.map.save(o.save_prefix + "_" + engine + "_drifted.fgm");
        map.save(o.save_prefix + "_" + engine + "_corrected.fgm");
        rebuilt.map.save(o.save_prefix + "_" + engine + "_truth.fgm");
      }
    }
  }
  if (o.from_file) std::filesystem::remove(tmp);
  std::printf("%s\n", fmt::format("[loop] {}: every scan corrected: {:.4f} % of the cells known "
                                  "in either map have the state of the rebuilt map (drifted map: "
                                  "{:.4f} %)",
                                  engine, 100 * agreement, 100 * before)
                          .c_str());
  return {{"engine", engine},
          {"backend", backend_name},
          {"scans", scans.size()},
          {"insert_ms_median", insert_median},
          {"insert_ms_p99", percentile(drift.ms, 0.99)},
          {"rebuild_ms", rebuilt.seconds * 1e3},
          {"agreement_after", agreement},
          {"agreement_before", before},
          {"rows", rows}};
}

int run(const Options& o) {
  auto source = openDataset(o.kitti);
  std::vector<Scan> scans;
  Scan s;
  while ((o.max_scans == 0 || scans.size() < o.max_scans) && source->next(s))
    scans.push_back(std::move(s));
  if (scans.empty()) throw IoError(o.kitti + ": no scans");
  size_t points = 0;
  for (const Scan& x : scans) points += x.cloud.size();
  std::printf("%s\n", fmt::format("{}: {} scans, {} points per scan, {} m, max range {} m",
                                  source->describe(), scans.size(), points / scans.size(),
                                  o.resolution_m, o.max_range_m)
                          .c_str());
  const std::vector<Eigen::Isometry3d> drifted = driftedPoses(o, scans);
  std::printf(
      "| engine | k corrected | ms total | ms per scan | per scan / one insertion | "
      "rebuild ms | speed-up vs rebuild |\n|---|---|---|---|---|---|---|\n");
  nlohmann::json all = nlohmann::json::array();
  for (const std::string& engine : o.backends) all.push_back(runBackend(engine, o, scans, drifted));
  if (!o.json_path.empty()) {
    nlohmann::json j = {{"input", o.kitti},
                        {"resolution_m", o.resolution_m},
                        {"max_range_m", o.max_range_m},
                        {"points_per_scan", points / scans.size()},
                        {"engines", all}};
    std::ofstream(o.json_path) << j.dump(1) << "\n";
  }
  return 0;
}

}  // namespace
}  // namespace fragg::bench

int main(int argc, char** argv) {
  fragg::bench::Options o;
  CLI::App app("fragg_map_loop_bench: pose correction (remove + re-insert) against a rebuild");
  app.add_option("--kitti", o.kitti, "KITTI folder with the true poses (poses.txt)")->required();
  app.add_option("--odom", o.odom, "Drifting poses (KITTI format); default: made-up drift");
  app.add_option("--backends", o.backends, "Engines (cpu, cuda, cuda+pageable, ...)");
  app.add_option("--ks", o.ks, "Numbers of scans to correct (the last k)");
  app.add_option("--resolution", o.resolution_m, "Voxel edge (m)")->capture_default_str();
  app.add_option("--max-range", o.max_range_m, "Max range (m)")->capture_default_str();
  app.add_option("--drift-m", o.drift_m, "Made-up drift per scan (m)")->capture_default_str();
  app.add_option("--drift-rad", o.drift_rad, "Made-up yaw drift per scan (rad)")
      ->capture_default_str();
  app.add_option("--scans", o.max_scans, "Use the first N scans (0 = all)");
  app.add_flag("--from-file", o.from_file,
               "Correct a map loaded from a file (cold: every block on the host) instead of one "
               "just built in this process");
  app.add_option("--threads", o.threads, "CPU threads (0 = every core)");
  app.add_option("--json", o.json_path, "Write the figures as JSON");
  app.add_option("--save-maps", o.save_prefix,
                 "Save PREFIX_<engine>_{drifted,corrected,truth}.fgm (for fragg_map eval)");
  CLI11_PARSE(app, argc, argv);
  try {
    return fragg::bench::run(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fragg_map_loop_bench: error: %s\n", e.what());
    return 1;
  }
}
