#include "bench/workloads.h"

#include <fmt/format.h>

#include <filesystem>

#include "bench/synthetic_lidar.h"
#include "fragg_map/errors.h"
#include "fragg_map/io/point_file.h"
#include "fragg_map/io/pose_file.h"

namespace fragg::bench {
namespace {

std::vector<Scan> readAll(const std::string& input, size_t max_scans = 0) {
  std::vector<Scan> scans;
  auto src = openDataset(input);
  Scan s;
  while ((max_scans == 0 || scans.size() < max_scans) && src->next(s)) scans.push_back(s);
  return scans;
}

Scan fileScan(const std::string& path, const Eigen::Isometry3d& T = Eigen::Isometry3d::Identity()) {
  Scan s;
  s.cloud = readPointFile(path);
  s.T_map_sensor = T;
  return s;
}

}  // namespace

std::vector<Workload> realWorkloads(const std::string& data_dir, const WantFn& want) {
  std::vector<Workload> out;
  const std::string d = data_dir + "/";
  if (want("velodyne_pair")) {
    const Eigen::Isometry3d T = readMatrix4(d + "small_gicp_pair/T_target_source.txt");
    out.push_back({"velodyne_pair (HDL-32E, 2 scans)",
                   {fileScan(d + "small_gicp_pair/target.ply"),
                    fileScan(d + "small_gicp_pair/source.ply", T)},
                   0.05,
                   30.0,
                   "real"});
  }
  if (want("room"))
    out.push_back({"room_scans (2 x 112k indoor)",
                   {fileScan(d + "pcl_room_scans/room_scan1.pcd"),
                    fileScan(d + "pcl_room_scans/room_scan2.pcd")},
                   0.05,
                   -1.0,
                   "real"});
  if (want("vls128"))
    out.push_back({"vls128 (208k, outdoor)",
                   {fileScan(d + "nebula_single_scans/vls128_1585897255376374245.pcd")},
                   0.05,
                   30.0,
                   "real"});
  if (want("rgbd"))
    out.push_back(
        {"rgbd (5 x 640x480 Kinect)", readAll(d + "slambook2_ch5_rgbd"), 0.05, -1.0, "real"});
  return out;
}

std::vector<Workload> syntheticWorkloads(int scans, double resolution_m, const WantFn& want) {
  std::vector<Workload> out;
  for (double range : {30.0, 50.0}) {
    const std::string name = fmt::format("synthetic lidar360 (180k pts, {:.0f} m)", range);
    if (!want(name) || scans <= 0) continue;
    SyntheticLidar sim{SyntheticLidarOptions()};
    Workload w{name, {}, resolution_m, range, "synthetic"};
    for (int i = 0; i < scans; ++i) w.scans.push_back(sim.scan(i));
    out.push_back(std::move(w));
  }
  return out;
}

std::vector<Workload> simWorkloads(const std::string& dir, size_t max_scans, const WantFn& want) {
  std::vector<Workload> out;
  auto folder = [&](const std::string& name) {
    const std::string path = dir + "/" + name;
    if (!std::filesystem::is_directory(path))
      throw IoError(path + ": no such workload (run scripts/make_workloads.sh --out " + dir + ")");
    return path;
  };
  const bool w1_30 = want("W1 lidar360 30 m"), w1_50 = want("W1 lidar360 50 m");
  if (w1_30 || w1_50) {
    const std::vector<Scan> scans = readAll(folder("w1_lidar360"), max_scans);
    if (w1_30) out.push_back({"W1 lidar360 30 m", scans, 0.05, 30.0, "W1"});
    if (w1_50) out.push_back({"W1 lidar360 50 m", scans, 0.05, 50.0, "W1"});
  }
  std::vector<Scan> depth;
  for (double res : {0.02, 0.05, 0.10, 0.20}) {
    const std::string name = fmt::format("W2 depth {:.0f} cm", res * 100);
    if (!want(name)) continue;
    if (depth.empty()) depth = readAll(folder("w2_depth"), max_scans);
    out.push_back({name, depth, res, -1.0, "W2"});
  }
  return out;
}

}  // namespace fragg::bench
