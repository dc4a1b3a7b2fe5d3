// A simulated spinning LiDAR: beams x azimuth steps rays cast against the scene, organised
// (row = beam from the highest elevation down, column = azimuth from +x counter-clockwise),
// NaN where a ray has no return. Sensor frame: x forward, y left, z up.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/point_cloud.h"

namespace fragg::sim {

struct LidarSpec {
  int beams = 32;  ///< 16, 32, 64, 128...
  int azimuth_steps = 1024;
  double elevation_min_deg = -25.0;
  double elevation_max_deg = 15.0;
  double min_range_m = 0.3;    ///< closer hits give no return
  double max_range_m = 80.0;   ///< farther hits give no return
  double range_noise_m = 0.0;  ///< standard deviation, added along the ray
  double dropout = 0.0;        ///< probability that a return is lost

  /// Throws InvalidArgument naming the bad field.
  void validate() const;
  /// Unit direction of (beam, column) in the sensor frame.
  Eigen::Vector3f direction(int beam, int column) const;
};

/// One scan from pose T_map_sensor. Noise and dropout are drawn from (seed, frame, ray), so the
/// same arguments give the same cloud whatever the thread count. Multithreaded (OpenMP).
/// With `movers` (the moving objects' mesh at the scan's time), rays are cast against both
/// meshes and `dynamic_labels` (when given) gets one flag a point of the cloud: 1 where the
/// return is from a mover (the nearer surface), 0 elsewhere (static returns and no-returns).
PointCloud simulateLidar(const geometry::MeshBvh& scene, const LidarSpec& spec,
                         const Eigen::Isometry3d& T_map_sensor, uint64_t seed, uint64_t frame,
                         const geometry::MeshBvh* movers = nullptr,
                         std::vector<uint8_t>* dynamic_labels = nullptr);

}  // namespace fragg::sim
