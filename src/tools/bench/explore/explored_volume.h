// The explored volume of an exploration run, measured against the scene's ground truth.
//
// The reference cells are the map cells whose centre lies in the scenario's box and that an
// ideal sensor could observe: cells whose centre is outside every solid of the scene (free in
// the ground truth), and surface cells (centre inside a solid, with one of the 6 face
// neighbours in the box outside every solid). Cells deep inside solids are left out: no sensor
// sees them. The explored fraction is the share of the reference cells that the map knows
// (free or occupied, by the map's own rule, unknown band included); known cells deep inside
// solids do not count.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/key.h"
#include "fragg_map/map.h"

namespace fragg::explore {

class ExploredVolume {
 public:
  /// Classifies every cell of the box at `resolution_m` (OpenMP, `threads` 0 = every core).
  ExploredVolume(const geometry::MeshBvh& scene, const Eigen::Vector3d& box_min_m,
                 const Eigen::Vector3d& box_max_m, double resolution_m, int threads = 0);

  uint64_t referenceCells() const { return reference_cells_; }
  uint64_t boxCells() const { return reference_.size(); }
  double cellVolume_m3() const { return cell_m3_; }
  /// Reference cells the map knows (the map's resolution must be the one given above).
  uint64_t knownReferenceCells(const Map& map) const;

 private:
  /// Index of a key in the box grid, or -1 outside.
  int64_t indexOf(const VoxelKey& k) const;

  VoxelKey lo_, hi_;  ///< inclusive key range of the cells whose centre is in the box
  int64_t nx_ = 0, ny_ = 0, nz_ = 0;
  std::vector<uint8_t> reference_;  ///< 1: reference cell
  uint64_t reference_cells_ = 0;
  double resolution_m_ = 0.0, cell_m3_ = 0.0;
};

}  // namespace fragg::explore
