#include "fragg_map/sim/dynamic_quality.h"

#include <cmath>
#include <string>

#include "fragg_map/errors.h"

namespace fragg::sim {
namespace {

bool occupiedCell(const Map& map, const Cell* c, bool octomap_threshold) {
  if (!c || !c->observed()) return false;
  return octomap_threshold ? c->log_odds_fx >= 0 : map.state(*c) == CellState::kOccupied;
}

}  // namespace

void addLabelledScan(const Map& map, const PointCloud& cloud_S,
                     const Eigen::Isometry3d& T_map_sensor, const std::vector<uint8_t>& labels,
                     bool octomap_threshold, DynamicQuality& quality, double max_range_m) {
  size_t finite = 0;
  for (const Eigen::Vector3f& p : cloud_S.points_S) finite += p.allFinite() ? 1 : 0;
  if (finite != labels.size())
    throw InvalidArgument(std::to_string(labels.size()) + " labels for " + std::to_string(finite) +
                          " finite points");
  size_t k = 0;
  for (const Eigen::Vector3f& p : cloud_S.points_S) {
    if (!p.allFinite()) continue;
    const bool dynamic = labels[k++] != 0;
    if (p.cast<double>().norm() > max_range_m) continue;
    const Cell* c = map.findCell(map.keyOf(T_map_sensor * p.cast<double>()));
    const bool occupied = occupiedCell(map, c, octomap_threshold);
    if (dynamic) {
      ++quality.dynamic_points;
      quality.dynamic_removed += occupied ? 0 : 1;
    } else {
      ++quality.static_points;
      quality.static_kept += occupied ? 1 : 0;
    }
  }
}

void countGhostCells(const Map& map, const geometry::MeshBvh& static_scene, bool octomap_threshold,
                     DynamicQuality& quality) {
  const float near_m = static_cast<float>(std::sqrt(3.0) / 2.0 * map.resolution());
  const BlockView blocks = map.blockView();
  const std::vector<BlockRef> all = blocks.all();
  const Eigen::AlignedBox3f bounds = static_scene.bounds();
  uint64_t occupied = 0, ghosts = 0;
#pragma omp parallel for schedule(dynamic, 16) reduction(+ : occupied, ghosts)
  for (size_t n = 0; n < all.size(); ++n) {
    const Block& block = *all[n].block;
    for (int ci = 0; ci < kCellsPerBlock; ++ci) {
      if (!occupiedCell(map, &block.cells[ci], octomap_threshold)) continue;
      ++occupied;
      const Eigen::Vector3f p = map.centerOf(voxelKeyOf(all[n].key, ci)).cast<float>();
      if (static_scene.withinDistance(p, near_m)) continue;
      if (bounds.contains(p) && static_scene.inside(p)) continue;
      ++ghosts;
    }
  }
  quality.occupied += occupied;
  quality.ghost_cells += ghosts;
}

}  // namespace fragg::sim
