// A synthetic 360-degree LiDAR in a campus-like scene of analytic primitives (ground, box
// buildings, cylinder trees), deterministic for a seed. Stands in for the simulator's W1
// workload in the benchmark until fragg_map_sim exists.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "fragg_map/io/dataset.h"

namespace fragg::bench {

struct SyntheticLidarOptions {
  int beams = 128;
  int azimuth_steps = 1406;  // 128 x 1406 = 179,968 points per scan
  double elevation_min_deg = -25.0;
  double elevation_max_deg = 15.0;
  double max_return_m = 80.0;  // no return (NaN) beyond this
  double sensor_height_m = 1.8;
  double step_m = 0.5;  // distance between scans along the path
  uint32_t seed = 1;
};

class SyntheticLidar {
 public:
  explicit SyntheticLidar(const SyntheticLidarOptions& options);
  /// Scan `index` along the path (sensor frame cloud + pose).
  Scan scan(int index) const;

 private:
  struct Box {
    Eigen::Vector3d lo, hi;
  };
  struct Cylinder {
    Eigen::Vector2d centre;
    double radius, height;
  };
  double castRay(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const;

  SyntheticLidarOptions options_;
  std::vector<Box> boxes_;
  std::vector<Cylinder> trees_;
};

}  // namespace fragg::bench
