// The paging tests' corridor drive with a person walking in it (MapParams::dynamic under
// paging: dynamic_paging_test.cpp on the CPU, test/gpu/dynamic_paging_gpu_test.cpp on CUDA).
#pragma once

#include <Eigen/Geometry>

#include "fragg_map/map_params.h"
#include "fragg_map/point_cloud.h"
#include "paging_scenes.h"

namespace fragg::test {

/// A person (a 0.3 x 0.3 m column, 1.8 m tall, its sensor-facing side) who walks across the
/// corridor 5 m ahead of the sensor (behind it on the way back), back and forth, one step a
/// scan: points in the sensor frame added to the corridor's scan `scan` of `scans`.
inline void addWalker(int scan, int scans, const Eigen::Isometry3d& T_map_sensor,
                      PointCloud* cloud) {
  const int phase = scan % 24;
  const double y_m = -3.0 + 0.25 * (phase < 12 ? phase : 24 - phase);
  const bool out = scan < scans / 2;
  const double x_m = T_map_sensor.translation().x() + (out ? 5.0 : -5.0);
  const double facing_m = out ? -0.15 : 0.15;  // the side the sensor sees
  const Eigen::Isometry3d T_sensor_map = T_map_sensor.inverse();
  for (int z = 1; z <= 18; ++z)
    for (int dy = -1; dy <= 1; ++dy)
      cloud->points_S.push_back(
          (T_sensor_map * Eigen::Vector3d(x_m + facing_m, y_m + 0.1 * dy, 0.1 * z)).cast<float>());
  cloud->width = static_cast<uint32_t>(cloud->points_S.size());
}

/// The corridor's scan `scan` of `scans` with the walker in it.
inline PointCloud walkerCorridorScan(int scan, int scans, const Eigen::Isometry3d& T_map_sensor) {
  PointCloud cloud = corridorScan(T_map_sensor);
  addWalker(scan, scans, T_map_sensor, &cloud);
  return cloud;
}

/// corridorParams with dynamic mapping on under `rule` (known radius 2 cells).
inline MapParams dynamicCorridorParams(VoidSpaceRule rule, Backend backend = Backend::kCpu) {
  MapParams p = corridorParams(backend);
  p.dynamic.enabled = true;
  p.dynamic.rule = rule;
  p.dynamic.known_radius_cells = 2;
  return p;
}

}  // namespace fragg::test
