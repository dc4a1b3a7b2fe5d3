// fragg_map_ros_overhead: what the map server spends per cloud outside insertion, on the
// synthetic 128 x 1406 LiDAR (179,968 points): PointCloud2 -> points (a Velodyne-like layout:
// x y z intensity, point_step 16, organised) and the incremental marker update
// (changedBlockMarkersWire: the changed chunks encoded in the wire layout) after each insertion,
// or, with --marker-rate, when the server's RateThrottle lets one out for clouds arriving at
// --cloud-rate (the skipped clouds' changes go out with the next update, and a last update flushes
// what is pending at the end, as the server's timer does); the insertion itself is timed for
// reference. The last line is what the server's path (conversion + insertion, + marker updates
// unless --no-markers) sustains on this machine in clouds per second, with the process's CPU time
// over that wall time (the share of the cores it got: other programs count against it on a shared
// machine). Map::memory(), which the server's ~stats reads after every cloud, is timed beside them
// (not in the path).
//   fragg_map_ros_overhead [--scans N] [--resolution M] [--max-range M]
//                          [--cloud-rate HZ] [--marker-rate HZ] [--no-markers]
//                          [--beams N --columns N]   (128 x 1406 = 179,968 points a cloud)
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/PointField.h>
#include <sys/resource.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <vector>

#include "bench/synthetic_lidar.h"
#include "bench/velodyne_msg.h"
#include "fragg_map/map.h"
#include "fragg_map/ros/block_markers.h"
#include "fragg_map/ros/cloud_from_msg.h"
#include "fragg_map/ros/rate_throttle.h"
#include "percentile.h"

namespace {

/// User + system CPU time of the process so far [s].
double processCpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("per-cloud overhead of the map server outside insertion");
  int scans = 10;
  double resolution_m = 0.05, max_range_m = 30.0, cloud_rate_hz = 10.0, marker_rate_hz = 0.0;
  app.add_option("--scans", scans, "scans along the synthetic path")->check(CLI::PositiveNumber);
  app.add_option("--resolution", resolution_m, "voxel edge [m]");
  app.add_option("--max-range", max_range_m, "sensor max range [m]");
  app.add_option("--cloud-rate", cloud_rate_hz, "clouds per second (sensor time)")
      ->check(CLI::PositiveNumber);
  app.add_option("--marker-rate", marker_rate_hz,
                 "most marker updates per second, as the server's marker_rate (0: every cloud)")
      ->check(CLI::NonNegativeNumber);
  bool no_markers = false;
  app.add_flag("--no-markers", no_markers, "no marker updates (nobody subscribes to markers)");
  fragg::bench::SyntheticLidarOptions lidar_options;
  app.add_option("--beams", lidar_options.beams, "LiDAR rows")->check(CLI::PositiveNumber);
  app.add_option("--columns", lidar_options.azimuth_steps, "LiDAR columns (azimuth steps)")
      ->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);

  fragg::bench::SyntheticLidar lidar{lidar_options};
  fragg::MapParams params;
  params.resolution_m = resolution_m;
  params.backend = fragg::Backend::kCpu;
  fragg::Map map(params);
  fragg::ros::MarkerLedger ledger;
  const fragg::ros::MarkerStyle style;
  fragg::ros::RateThrottle throttle(marker_rate_hz);
  std::vector<double> convert_ms, update_ms, insert_ms, overhead_ms, memory_ms;
  double markers_total_ms = 0.0;
  size_t points = 0, markers_sent = 0, blocks_changed = 0, known_voxels = 0;
  // One marker update: the blocks changed since the last one, counted and converted.
  auto markerUpdate = [&]() {
    const uint64_t before = ledger.publishedRevision();
    blocks_changed += map.changedBlocksSince(before, fragg::BlockChange::kOccupied).size();
    const auto t0 = std::chrono::steady_clock::now();
    const auto markers = fragg::ros::changedBlockMarkersWire(map, style, ros::Time(), &ledger);
    update_ms.push_back(msSince(t0));
    markers_total_ms += update_ms.back();
    markers_sent += markers.markers.size();
    return update_ms.back();
  };
  double path_wall_ms = 0.0, path_cpu_s = 0.0;  // conversion + insertion (+ markers)
  for (int i = 0; i < scans; ++i) {
    const fragg::Scan scan = lidar.scan(i);
    const sensor_msgs::PointCloud2 msg = fragg::bench::velodyneLikeMsg(scan.cloud);
    const double cpu0_s = processCpuSeconds();
    auto t0 = std::chrono::steady_clock::now();
    const fragg::PointCloud cloud = fragg::ros::cloudFromMsg(msg);
    convert_ms.push_back(msSince(t0));
    points = cloud.size();
    t0 = std::chrono::steady_clock::now();
    map.insert(cloud, scan.T_map_sensor, fragg::SensorModel::autoFromCloud(0.0, max_range_m));
    insert_ms.push_back(msSince(t0));
    // What ~stats reads after every cloud when it is latched (the default) or subscribed:
    // Map::memory() (known voxels, blocks, bytes). Timed, not counted in the path.
    t0 = std::chrono::steady_clock::now();
    const fragg::MemoryStats memory = map.memory();
    memory_ms.push_back(msSince(t0));
    known_voxels = memory.known_voxels;
    const double now_s = i / cloud_rate_hz;  // the cloud's arrival, in sensor time
    double markers_ms = 0.0;
    if (!no_markers && throttle.due(now_s)) {
      markers_ms = markerUpdate();
      throttle.published(now_s);
    }
    overhead_ms.push_back(convert_ms.back() + markers_ms);
    path_wall_ms += convert_ms.back() + insert_ms.back() + markers_ms;
    path_cpu_s += processCpuSeconds() - cpu0_s;
  }
  // What the last clouds changed goes out once the clouds stop (the server's flush timer).
  if (!no_markers && ledger.publishedRevision() != map.revision()) markerUpdate();
  const size_t updates = std::max<size_t>(update_ms.size(), 1);
  using fragg::tools::percentile;
  std::printf(
      "%d scans of %zu points, %.3f m, max range %.0f m, CPU backend, %zu blocks, %zu known "
      "voxels\n",
      scans, points, resolution_m, max_range_m, map.blockCount(), known_voxels);
  std::printf("clouds at %.1f Hz, marker_rate %.1f Hz: %zu marker updates\n", cloud_rate_hz,
              marker_rate_hz, updates);
  std::printf("%-28s %10s %10s %10s\n", "ms per cloud", "median", "p99", "max");
  auto row = [&](const char* name, const std::vector<double>& v) {
    std::printf("%-28s %10.2f %10.2f %10.2f\n", name, percentile(v, 0.5), percentile(v, 0.99),
                percentile(v, 1.0));
  };
  row("conversion (PointCloud2)", convert_ms);
  if (!update_ms.empty()) row("marker update (per update)", update_ms);
  row("overhead (per cloud)", overhead_ms);
  row("insertion (reference)", insert_ms);
  row("Map::memory (~stats)", memory_ms);
  double convert_total_ms = 0.0;
  for (double ms : convert_ms) convert_total_ms += ms;
  std::printf("mean per cloud: conversion %.2f ms + markers %.2f ms = overhead %.2f ms\n",
              convert_total_ms / scans, markers_total_ms / scans,
              (convert_total_ms + markers_total_ms) / scans);
  std::printf("per update: blocks whose occupied cells changed %.0f, markers sent %.0f (means)\n",
              double(blocks_changed) / updates, double(markers_sent) / updates);
  std::printf(
      "sustained: %.2f clouds/s (conversion + insertion%s, mean %.1f ms a cloud), CPU time %.0f "
      "%% of that wall time\n",
      1000.0 * scans / path_wall_ms, no_markers ? "" : " + markers", path_wall_ms / scans,
      100.0 * path_cpu_s / (path_wall_ms / 1000.0));
  return 0;
}
