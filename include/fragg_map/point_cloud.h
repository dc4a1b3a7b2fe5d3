// A point cloud in the sensor frame. Organised clouds (height > 1) keep a NaN point where the
// sensor had no return, so that rays without a return can clear free space if asked.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace fragg {

struct PointCloud {
  std::vector<Eigen::Vector3f> points_S;  ///< sensor frame, metres; NaN = no return
  uint32_t width = 0;                     ///< organised width (0 when unorganised)
  uint32_t height = 1;                    ///< organised height (1 when unorganised)

  size_t size() const { return points_S.size(); }
  bool empty() const { return points_S.empty(); }
  bool organised() const { return height > 1 && size_t{width} * height == points_S.size(); }
};

}  // namespace fragg
