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

/// Free in the static truth: the cell centre `p` lies farther than `near_m` from the scene's
/// surface and outside its solids.
bool freeInStaticTruth(const Eigen::Vector3f& p, const geometry::MeshBvh& static_scene,
                       const Eigen::AlignedBox3f& bounds, float near_m) {
  if (static_scene.withinDistance(p, near_m)) return false;
  return !(bounds.contains(p) && static_scene.inside(p));
}

float nearDistance(const Map& map) {
  return static_cast<float>(std::sqrt(3.0) / 2.0 * map.resolution());
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
  const float near_m = nearDistance(map);
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
      if (freeInStaticTruth(p, static_scene, bounds, near_m)) ++ghosts;
    }
  }
  quality.occupied += occupied;
  quality.ghost_cells += ghosts;
}

std::vector<VoxelKey> ghostCellKeys(const Map& map, const geometry::MeshBvh& static_scene,
                                    bool octomap_threshold) {
  const float near_m = nearDistance(map);
  const std::vector<BlockRef> all = map.blockView().all();
  const Eigen::AlignedBox3f bounds = static_scene.bounds();
  std::vector<std::vector<VoxelKey>> per_block(all.size());
#pragma omp parallel for schedule(dynamic, 16)
  for (size_t n = 0; n < all.size(); ++n) {
    const Block& block = *all[n].block;
    for (int ci = 0; ci < kCellsPerBlock; ++ci) {
      if (!occupiedCell(map, &block.cells[ci], octomap_threshold)) continue;
      const VoxelKey key = voxelKeyOf(all[n].key, ci);
      if (freeInStaticTruth(map.centerOf(key).cast<float>(), static_scene, bounds, near_m))
        per_block[n].push_back(key);
    }
  }
  std::vector<VoxelKey> keys;
  for (const auto& v : per_block) keys.insert(keys.end(), v.begin(), v.end());
  return keys;
}

}  // namespace fragg::sim
