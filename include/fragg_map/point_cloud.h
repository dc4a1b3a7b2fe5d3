// A point cloud in the sensor frame. Organised clouds (height > 1) keep a NaN point where the
// sensor had no return, so that rays without a return can clear free space if asked. Points
// may be marked free-only (octomap_server's ground points, filter_ground): their rays clear
// the cells up to the point and leave the point's own cell as it was, like a ray clipped at
// max range.
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
  /// Empty (no free-only point), or one flag per point: non-zero marks a free-only point.
  std::vector<uint8_t> free_only;

  size_t size() const { return points_S.size(); }
  bool empty() const { return points_S.empty(); }
  bool hasFreeOnly() const { return !free_only.empty(); }
  bool freeOnly(size_t i) const { return !free_only.empty() && free_only[i] != 0; }
  bool organised() const { return height > 1 && size_t{width} * height == points_S.size(); }
};

}  // namespace fragg
