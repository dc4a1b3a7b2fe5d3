// The scene of the autosave kill test (map_image_test.cpp, map_save_loop.cpp): scan k of a
// deterministic sequence, so that the test rebuilds the map a killed process had saved.
#pragma once

#include <Eigen/Geometry>

#include "fragg_map/map.h"
#include "test_scenes.h"

namespace fragg::test {

inline MapParams saveLoopParams() {
  MapParams p;
  p.resolution_m = 0.05;
  p.backend = Backend::kCpu;
  p.threads = 1;
  p.scans.keep = true;  // the kept-scan section is written too
  return p;
}

/// Inserts scan `k` (0-based): a room scan from a sensor that moves 7 cm per scan.
inline void insertSaveLoopScan(Map& map, int k) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.07 * k, 0.03 * (k % 5), 0.5);
  map.insert(roomScan(3.0 + 0.1 * (k % 3), 1.0, 2.0, 8, 180), T, SensorModel::autoFromCloud(),
             1000 + k, "lidar");
}

}  // namespace fragg::test
