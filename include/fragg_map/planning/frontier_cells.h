// Frontier cells (the paper's definition): free cells with at least one unknown cell among
// their 26 neighbours. Unknown means never observed, inside the occupancy model's unknown
// band, or in a block that does not exist; neighbours in other blocks count (a frontier crosses
// block borders). Optional filters, off by default, keep a subset: a box, a height band and a
// minimum distance to occupied cells.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "fragg_map/key.h"
#include "fragg_map/map.h"
#include "fragg_map/planning/query_control.h"

namespace fragg::planning {

struct FrontierFilter {
  /// Keep cells whose centre lies in [box_min_m, box_max_m] (map frame).
  bool use_box = false;
  Eigen::Vector3d box_min_m = Eigen::Vector3d::Zero(), box_max_m = Eigen::Vector3d::Zero();
  /// Keep cells whose centre's z lies in [min_z_m, max_z_m].
  bool use_height = false;
  double min_z_m = 0.0, max_z_m = 0.0;
  /// > 0: drop cells with an occupied cell whose centre is closer than this (metres).
  double min_obstacle_distance_m = 0.0;

  /// Throws InvalidArgument: non-finite or inverted box or band, negative or NaN distance.
  void validate() const;
  /// Whether a frontier cell passes (the distance test reads `map`).
  bool keeps(const Map& map, const BlockView& view, const VoxelKey& key) const;
  /// The box and height tests alone, for a cell centred at `centre_m` (map frame).
  [[nodiscard]] bool keepsCentre(const Eigen::Vector3d& centre_m) const;
  bool any() const { return use_box || use_height || min_obstacle_distance_m > 0.0; }
};

/// The order frontier results are returned in: by block (z, then y, then x block key), then by
/// cell index within the block (cellIndexOf: local z, y, x).
bool frontierOrder(const VoxelKey& a, const VoxelKey& b);
bool blockOrder(const BlockKey& a, const BlockKey& b);

/// Every frontier cell of the map that passes `filter`, sorted by frontierOrder; blocks examined in
/// parallel (`threads` OpenMP threads, 0 = every core). Hold the map's read lock.
/// `control`: a deadline or a cancel flag (QueryStopped is thrown when either comes).
std::vector<VoxelKey> findFrontierCells(const Map& map, const FrontierFilter& filter = {},
                                        int threads = 0, const QueryControl* control = nullptr);

/// Frontier cells of one block (those passing `filter`), as cell indices (cellIndexOf)
/// in increasing order; empty when the block does not exist.
std::vector<uint16_t> frontierCellsOfBlock(const Map& map, const BlockView& view,
                                           const BlockKey& block, const FrontierFilter& filter);

}  // namespace fragg::planning
