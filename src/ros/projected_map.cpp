// Column projection of the map between two heights into an OccupancyGrid.
#include "fragg_map/ros/projected_map.h"

#include <cmath>
#include <cstdint>

#include "fragg_map/errors.h"
#include "fragg_map/ros/height_band.h"
#include "fragg_map/ros/speckles.h"

namespace fragg::ros {
using grid_value::kFree;
using grid_value::kOccupied;
using grid_value::kUnknown;

nav_msgs::OccupancyGrid projectedMap(const fragg::Map& map, double min_z_m, double max_z_m,
                                     const std::string& frame_id, const ::ros::Time& stamp,
                                     bool hide_speckles) {
  const HeightBand heights{min_z_m, max_z_m};
  heights.validate();
  nav_msgs::OccupancyGrid grid;
  grid.header.frame_id = frame_id;
  grid.header.stamp = stamp;
  grid.info.map_load_time = stamp;
  const double res_m = map.resolution();
  grid.info.resolution = static_cast<float>(res_m);
  grid.info.origin.orientation.w = 1.0;
  const fragg::KeyBounds bounds = map.bounds();
  if (bounds.empty) return grid;
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
