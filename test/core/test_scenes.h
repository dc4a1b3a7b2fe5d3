// Small synthetic inputs shared by the core tests.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "fragg_map/map.h"

namespace fragg::test {

/// Sensor at the centre of voxel (0,0,0) at 5 cm.
inline Eigen::Isometry3d sensorAtVoxelCentre(double res = 0.05) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d::Constant(res / 2);
  return T;
}

inline PointCloud cloudOf(std::initializer_list<Eigen::Vector3f> pts) {
  PointCloud c;
  c.points_S.assign(pts.begin(), pts.end());
  return c;
}

/// A 360-degree scan of a box room (walls at +-half_m, floor and ceiling), `rings` x `cols`.
inline PointCloud roomScan(double half_m, double floor_m, double ceil_m, int rings, int cols) {
  PointCloud c;
  c.width = cols;
  c.height = rings;
  for (int r = 0; r < rings; ++r) {
    const double el = (-30.0 + 60.0 * r / (rings - 1)) * M_PI / 180.0;
    for (int k = 0; k < cols; ++k) {
      const double az = 2 * M_PI * k / cols;
      const Eigen::Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                              std::sin(el));
      double t = 1e9;
      for (int a = 0; a < 2; ++a)
        if (std::fabs(d[a]) > 1e-9) t = std::min(t, half_m / std::fabs(d[a]));
      if (d.z() > 1e-9) t = std::min(t, ceil_m / d.z());
      if (d.z() < -1e-9) t = std::min(t, -floor_m / d.z());
      c.points_S.push_back((d * t).cast<float>());
    }
  }
  return c;
}

}  // namespace fragg::test
