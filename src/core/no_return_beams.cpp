#include "fragg_map/internal/no_return_beams.h"

#include <cmath>
#include <cstdint>

namespace fragg {

std::vector<Eigen::Vector3d> emptyBeamDirections(const PointCloud& cloud, const LidarBeams& beams) {
  const size_t columns = beams.columns;
  std::vector<uint8_t> returned(size_t{beams.rings()} * columns, 0);
  for (const Eigen::Vector3f& p : cloud.points_S) {
    if (!p.allFinite()) continue;
    const double x = p.x(), y = p.y(), z = p.z();
    const double horizontal = std::sqrt(x * x + y * y);
    if (horizontal == 0.0 && z == 0.0) continue;  // (0,0,0): a no-return marker
    const int ring = beams.ringOf(std::atan2(z, horizontal));
    if (ring < 0) continue;
    returned[size_t(ring) * columns + beams.columnOf(std::atan2(y, x))] = 1;
  }
  std::vector<Eigen::Vector3d> dirs_S;
  for (uint32_t r = 0; r < beams.rings(); ++r)
    for (uint32_t c = 0; c < columns; ++c)
      if (!returned[size_t(r) * columns + c]) dirs_S.push_back(beams.direction(r, c));
  return dirs_S;
}

}  // namespace fragg
