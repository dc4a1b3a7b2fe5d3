#include "fragg_map/internal/region_reach.h"

#include <omp.h>

#include <cmath>
#include <cstdint>

#include "fragg_map/internal/thread_count.h"
#include "fragg_map/raycast.h"

namespace fragg {

namespace {
/// Marks the regions of the segment a -> b (region units) in `grid` (the box lo + size), on the
/// insertion's traversal (raycast.h's DdaAxis / ddaStep in region units, from a reference
/// region so that the float parameters stay small).
void walkSegment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const int64_t lo[3],
                 const int64_t size[3], std::vector<uint8_t>& grid) {
  const auto axisOf = [](double from, double to) {
    const int ref = static_cast<int>(std::floor(from));
    DdaAxis d;
    d.init(ref, static_cast<float>(from - ref), static_cast<float>(to - ref));
    return d;
  };
  DdaAxis x = axisOf(a.x(), b.x()), y = axisOf(a.y(), b.y()), z = axisOf(a.z(), b.z());
  for (;;) {
    const int64_t off[3] = {x.cur - lo[0], y.cur - lo[1], z.cur - lo[2]};
    if (off[0] >= 0 && off[1] >= 0 && off[2] >= 0 && off[0] < size[0] && off[1] < size[1] &&
        off[2] < size[2])
      grid[static_cast<size_t>((off[2] * size[1] + off[1]) * size[0] + off[0])] = 1;
    if (x.remaining == 0 && y.remaining == 0 && z.remaining == 0) break;
    ddaStep(x, y, z);
  }
}
}  // namespace

std::vector<BlockKey> regionsReached(const PointCloud& cloud, const Eigen::Isometry3d& T_map_sensor,
                                     double max_range_m, double region_m, const BlockKey& region_lo,
                                     const BlockKey& region_hi, int threads, size_t max_rays,
                                     size_t max_regions) {
  std::vector<BlockKey> out;
  const int64_t lo[3] = {region_lo.x, region_lo.y, region_lo.z};
  const int64_t size[3] = {int64_t{region_hi.x} - region_lo.x + 1,
                           int64_t{region_hi.y} - region_lo.y + 1,
                           int64_t{region_hi.z} - region_lo.z + 1};
  if (size[0] <= 0 || size[1] <= 0 || size[2] <= 0 || !(region_m > 0.0)) return out;
  const double cells = double(size[0]) * double(size[1]) * double(size[2]);
  if (cells > double(max_regions)) return out;
  const size_t n_cells = static_cast<size_t>(cells);
  const Eigen::Matrix3d R = T_map_sensor.linear();
  const Eigen::Vector3d origin = T_map_sensor.translation() / region_m;
  const size_t points = cloud.points_S.size();
  const size_t stride = max_rays > 0 && points > max_rays ? (points + max_rays - 1) / max_rays : 1;
  const long n = static_cast<long>((points + stride - 1) / stride);  // rays walked
  std::vector<uint8_t> grid(n_cells, 0);
#pragma omp parallel num_threads(threadCount(threads))
  {
    std::vector<uint8_t> mine(n_cells, 0);
#pragma omp for schedule(static)
    for (long i = 0; i < n; ++i) {
      const Eigen::Vector3f& p = cloud.points_S[static_cast<size_t>(i) * stride];
      if (!p.allFinite()) continue;
      Eigen::Vector3d d = p.cast<double>();
      const double r = d.norm();
      if (!(r > 0.0)) continue;
      if (max_range_m > 0.0 && r > max_range_m) d *= max_range_m / r;
      walkSegment(origin, origin + R * d / region_m, lo, size, mine);
    }
#pragma omp critical
    for (size_t j = 0; j < n_cells; ++j) grid[j] |= mine[j];
  }
  for (int64_t z = 0; z < size[2]; ++z)
    for (int64_t y = 0; y < size[1]; ++y)
      for (int64_t x = 0; x < size[0]; ++x)
        if (grid[static_cast<size_t>((z * size[1] + y) * size[0] + x)])
          out.push_back({static_cast<int32_t>(lo[0] + x), static_cast<int32_t>(lo[1] + y),
                         static_cast<int32_t>(lo[2] + z)});
  return out;
}

}  // namespace fragg
