// Column projection of the map between two heights into an OccupancyGrid.
#include "fragg_map/ros/projected_map.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "fragg_map/errors.h"
#include "fragg_map/ros/height_band.h"
#include "fragg_map/ros/speckles.h"

namespace fragg::ros {
using grid_value::kFree;
using grid_value::kOccupied;
using grid_value::kUnknown;

GridSpan octomapServerGridSpan(int64_t lo, int64_t hi, double resolution_m) {
  // liboctomap: keyToCoord = (key - 32768 + 0.5) * res; calcMinMax: leaf centre - size / 2,
  // then + size; coordToKey = floor(coordinate / res as 1.0 / res factor).
  const double half = resolution_m / 2.0;
  const double min_face = (static_cast<double>(lo) + 0.5) * resolution_m - half;
  const double max_face = ((static_cast<double>(hi) + 0.5) * resolution_m - half) + resolution_m;
  // octomap_server pads to include [-minSize / 2, minSize / 2] (0 by default): the origin;
  // it keys the faces as an octomap::point3d, i.e. rounded to float first.
  const double factor = 1.0 / resolution_m;
  const float lo_face = static_cast<float>(std::min(min_face, -0.0));
  const float hi_face = static_cast<float>(std::max(max_face, 0.0));
  GridSpan span;
  span.lo = static_cast<int64_t>(std::floor(factor * static_cast<double>(lo_face)));
  span.hi = static_cast<int64_t>(std::floor(factor * static_cast<double>(hi_face)));
  return span;
}

nav_msgs::OccupancyGrid projectedMap(const fragg::Map& map, double min_z_m, double max_z_m,
                                     const std::string& frame_id, const ::ros::Time& stamp,
                                     bool hide_speckles, bool octomap_bounds) {
  const HeightBand heights{min_z_m, max_z_m};
  heights.validate();
  nav_msgs::OccupancyGrid grid;
  grid.header.frame_id = frame_id;
  grid.header.stamp = stamp;
  grid.info.map_load_time = stamp;
  const double res_m = map.resolution();
  grid.info.resolution = static_cast<float>(res_m);
  grid.info.origin.orientation.w = 1.0;
  fragg::KeyBounds bounds = map.bounds();
  if (bounds.empty) return grid;
  if (octomap_bounds) {
    const GridSpan x = octomapServerGridSpan(bounds.min.x, bounds.max.x, res_m);
    const GridSpan y = octomapServerGridSpan(bounds.min.y, bounds.max.y, res_m);
    bounds.min.x = static_cast<int32_t>(x.lo);
    bounds.max.x = static_cast<int32_t>(x.hi);
    bounds.min.y = static_cast<int32_t>(y.lo);
    bounds.max.y = static_cast<int32_t>(y.hi);
  }
  const int64_t width = int64_t{bounds.max.x} - bounds.min.x + 1;
  const int64_t height = int64_t{bounds.max.y} - bounds.min.y + 1;
  grid.info.width = static_cast<uint32_t>(width);
  grid.info.height = static_cast<uint32_t>(height);
  grid.info.origin.position.x = bounds.min.x * res_m;
  grid.info.origin.position.y = bounds.min.y * res_m;
  grid.info.origin.position.z = 0.0;
  grid.data.assign(static_cast<size_t>(width * height), kUnknown);
  const fragg::BlockView blocks = map.blockView();
  map.forEachBlock([&](const fragg::BlockKey& key, const fragg::Block& b) {
    for (int c = 0; c < fragg::kCellsPerBlock; ++c) {
      const fragg::CellState s = map.state(b.cells[c]);
      if (s == fragg::CellState::kUnknown) continue;
      const fragg::VoxelKey v = fragg::voxelKeyOf(key, c);
      if (!heights.showsLayer(v.z, res_m)) continue;
      if (hide_speckles && s == fragg::CellState::kOccupied && isSpeckle(map, blocks, v)) continue;
      int8_t& cell = grid.data[static_cast<size_t>((int64_t{v.y} - bounds.min.y) * width +
                                                   (int64_t{v.x} - bounds.min.x))];
      if (s == fragg::CellState::kOccupied)
        cell = kOccupied;
      else if (cell == kUnknown)
        cell = kFree;
    }
  });
  return grid;
}

}  // namespace fragg::ros
