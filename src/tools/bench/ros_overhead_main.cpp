// fragg_map_ros_overhead: what the map server spends per cloud outside insertion, on the
// synthetic 128 x 1406 LiDAR (179,968 points): PointCloud2 -> points (a Velodyne-like layout:
// x y z intensity, point_step 16, organised) and the incremental marker update
// (changedBlockMarkers) after each insertion; the insertion itself is timed for reference.
//   fragg_map_ros_overhead [--scans N] [--resolution M] [--max-range M]
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/PointField.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <vector>

#include "bench/synthetic_lidar.h"
#include "fragg_map/map.h"
#include "fragg_map/ros/block_markers.h"
#include "fragg_map/ros/cloud_from_msg.h"
#include "percentile.h"

namespace {

sensor_msgs::PointCloud2 toMsg(const fragg::PointCloud& cloud) {
  sensor_msgs::PointCloud2 msg;
  msg.header.frame_id = "lidar";
  msg.width = cloud.organised() ? cloud.width : static_cast<uint32_t>(cloud.size());
  msg.height = cloud.organised() ? cloud.height : 1;
  const char* names[4] = {"x", "y", "z", "intensity"};
  for (uint32_t i = 0; i < 4; ++i) {
    sensor_msgs::PointField f;
    f.name = names[i];
    f.offset = 4 * i;
    f.datatype = sensor_msgs::PointField::FLOAT32;
    f.count = 1;
    msg.fields.push_back(f);
  }
  msg.point_step = 16;
  msg.row_step = 16 * msg.width;
  msg.data.assign(size_t{msg.row_step} * msg.height, 0);
  for (size_t i = 0; i < cloud.size(); ++i)
    std::memcpy(&msg.data[16 * i], cloud.points_S[i].data(), 12);
  return msg;
}

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("per-cloud overhead of the map server outside insertion");
  int scans = 10;
  double resolution_m = 0.05, max_range_m = 30.0;
  app.add_option("--scans", scans, "scans along the synthetic path")->check(CLI::PositiveNumber);
  app.add_option("--resolution", resolution_m, "voxel edge [m]");
  app.add_option("--max-range", max_range_m, "sensor max range [m]");
  CLI11_PARSE(app, argc, argv);

  fragg::bench::SyntheticLidar lidar{fragg::bench::SyntheticLidarOptions()};
  fragg::MapParams params;
  params.resolution_m = resolution_m;
  params.backend = fragg::Backend::kCpu;
  fragg::Map map(params);
  fragg_ros::MarkerLedger ledger;
  const fragg_ros::MarkerStyle style;
  std::vector<double> convert_ms, markers_ms, insert_ms, overhead_ms;
  size_t points = 0, markers_sent = 0, blocks_changed = 0;
  for (int i = 0; i < scans; ++i) {
    const fragg::Scan scan = lidar.scan(i);
    const sensor_msgs::PointCloud2 msg = toMsg(scan.cloud);
    auto t0 = std::chrono::steady_clock::now();
    const fragg::PointCloud cloud = fragg_ros::cloudFromMsg(msg);
    convert_ms.push_back(msSince(t0));
    points = cloud.size();
    t0 = std::chrono::steady_clock::now();
    map.insert(cloud, scan.T_map_sensor, fragg::SensorModel::autoFromCloud(0.0, max_range_m));
    insert_ms.push_back(msSince(t0));
    const uint64_t before = ledger.publishedRevision();
    map.blocks().forEach(
        [&](fragg::BlockIndex b) { blocks_changed += map.blocks().meta(b).changed_at > before; });
    t0 = std::chrono::steady_clock::now();
    const auto markers = fragg_ros::changedBlockMarkers(map, style, ros::Time(), &ledger);
    markers_ms.push_back(msSince(t0));
    markers_sent += markers.markers.size();
    overhead_ms.push_back(convert_ms.back() + markers_ms.back());
  }
  using fragg::tools::percentile;
  std::printf("%d scans of %zu points, %.3f m, max range %.0f m, CPU backend, %zu blocks\n", scans,
              points, resolution_m, max_range_m, map.blocks().size());
  std::printf("%-28s %10s %10s %10s\n", "ms per cloud", "median", "p99", "max");
  auto row = [&](const char* name, const std::vector<double>& v) {
    std::printf("%-28s %10.2f %10.2f %10.2f\n", name, percentile(v, 0.5), percentile(v, 0.99),
                percentile(v, 1.0));
  };
  row("conversion (PointCloud2)", convert_ms);
  row("incremental markers", markers_ms);
  row("overhead (sum)", overhead_ms);
  row("insertion (reference)", insert_ms);
  std::printf("blocks changed per cloud: %.0f, markers sent per cloud: %.0f (means)\n",
              double(blocks_changed) / scans, double(markers_sent) / scans);
  return 0;
}
