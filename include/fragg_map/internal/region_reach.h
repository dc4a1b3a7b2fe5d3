// The page-store regions a scan's rays pass through, walked on the host at region granularity:
// what a device backend pages in before its ray pass (Map::pageInAhead), so that a ray that
// reaches a paged-out region (a miss, the pass redone) is the exception, as on the CPU path,
// which pages in exactly the blocks its rays mark before it applies any.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <vector>

#include "fragg_map/key.h"
#include "fragg_map/point_cloud.h"

namespace fragg {

/// The regions in [region_lo, region_hi] (inclusive; region keys, regionOf() of block keys)
/// that the segment from the sensor's origin to each finite point of `cloud` (sensor frame; a
/// point farther than `max_range_m` > 0 ends at that range, as a free-only ray does) passes
/// through, each region of edge `region_m` metres in the map frame. Sorted by (z, y, x), no
/// duplicates; the parts of segments outside the box are not listed. Empty when the box holds
/// more than `max_regions` regions. `threads`: threadCount()'s setting. `max_rays` > 0: only
/// every k-th point is walked (k = ceil(points / max_rays)), a sample of the rays: neighbouring
/// rays of a dense scan cross the same regions (a region only a few rays reach may be missed).
[[nodiscard]] std::vector<BlockKey> regionsReached(
    const PointCloud& cloud, const Eigen::Isometry3d& T_map_sensor, double max_range_m,
    double region_m, const BlockKey& region_lo, const BlockKey& region_hi, int threads,
    size_t max_rays = 0, size_t max_regions = size_t{1} << 21);

}  // namespace fragg
