#include "fragg_map/planning/frontier_cells.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "fragg_map/errors.h"
#include "fragg_map/planning/frontier_tracker.h"
#include "frontier_masks.h"

namespace fragg::planning {

namespace {

bool obstacleWithin(const Map& map, const BlockView& view, const VoxelKey& key, double distance_m) {
  const double res = map.resolution();
  const int r = static_cast<int>(std::ceil(distance_m / res));
  const double limit_sq = (distance_m / res) * (distance_m / res);  // in cells^2
  for (int dz = -r; dz <= r; ++dz)
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx) {
        if (double(dx * dx + dy * dy + dz * dz) >= limit_sq) continue;
        const Cell* c = view.findCell({key.x + dx, key.y + dy, key.z + dz});
        if (c && map.state(*c) == CellState::kOccupied) return true;
      }
  return false;
}

}  // namespace

void FrontierFilter::validate() const {
  if (use_box) {
    if (!box_min_m.allFinite() || !box_max_m.allFinite())
      throw InvalidArgument("frontier box corners must be finite");
    if ((box_min_m.array() > box_max_m.array()).any())
      throw InvalidArgument("frontier box min corner must not exceed the max corner");
  }
  if (use_height) {
    if (!std::isfinite(min_z_m) || !std::isfinite(max_z_m))
      throw InvalidArgument("frontier height band must be finite");
    if (min_z_m > max_z_m)
      throw InvalidArgument(
          fmt::format("frontier height band is inverted ({} > {})", min_z_m, max_z_m));
  }
  if (!std::isfinite(min_obstacle_distance_m) || min_obstacle_distance_m < 0.0)
    throw InvalidArgument(fmt::format("frontier obstacle distance must be finite and >= 0, got {}",
                                      min_obstacle_distance_m));
}

bool FrontierFilter::keepsCentre(const Eigen::Vector3d& c) const {
  if (use_box && ((c.array() < box_min_m.array()).any() || (c.array() > box_max_m.array()).any()))
    return false;
  return !(use_height && (c.z() < min_z_m || c.z() > max_z_m));
}

bool FrontierFilter::keeps(const Map& map, const BlockView& view, const VoxelKey& key) const {
  if (!keepsCentre(map.centerOf(key))) return false;
  if (min_obstacle_distance_m > 0.0 && obstacleWithin(map, view, key, min_obstacle_distance_m))
    return false;
  return true;
}

bool blockOrder(const BlockKey& a, const BlockKey& b) {
  if (a.z != b.z) return a.z < b.z;
  if (a.y != b.y) return a.y < b.y;
  return a.x < b.x;
}

bool frontierOrder(const VoxelKey& a, const VoxelKey& b) {
  const BlockKey ba = blockKeyOf(a), bb = blockKeyOf(b);
  if (ba != bb) return blockOrder(ba, bb);
  return cellIndexOf(a) < cellIndexOf(b);
}

std::vector<uint16_t> frontierCellsOfBlock(const Map& map, const BlockView& view,
                                           const BlockKey& block, const FrontierFilter& filter) {
  std::vector<uint16_t> cells;
  if (!view.findBlock(block)) return cells;
  StateMasks masks[27];
  const StateMasks* around[27];
  for (int dz = -1, j = 0; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx, ++j) {
        // The map's state masks: no cell is read.
        const BlockStateMasks* m = view.findMasks({block.x + dx, block.y + dy, block.z + dz});
        if (m) masks[j] = statesOf(*m);
        around[j] = m ? &masks[j] : nullptr;
      }
  const FrontierBits bits = frontierBitsOf(around);
  for (int w = 0; w < kMaskWords; ++w)
    for (uint64_t m = bits.words[w]; m; m &= m - 1) {
      const uint16_t index = static_cast<uint16_t>(w * 64 + __builtin_ctzll(m));
      if (filter.any() && !filter.keeps(map, view, voxelKeyOf(block, index))) continue;
      cells.push_back(index);
    }
  return cells;
}

std::vector<VoxelKey> findFrontierCells(const Map& map, const FrontierFilter& filter, int threads,
                                        const QueryControl* control) {
  FrontierTracker tracker(filter, threads);  // validates the filter and the thread count
  tracker.update(map, control);
  checkQuery(control, "frontier cells");
  return tracker.cells();
}

}  // namespace fragg::planning
