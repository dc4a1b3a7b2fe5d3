// Frontier clusters: 26-connected components of frontier cells; components smaller than
// min_cells are dropped, components wider than max_extent_m are split in two along their
// principal axis (at the mean) until every piece fits. A cluster keeps its id from one call
// to the next while its cells are unchanged.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "fragg_map/key.h"
#include "fragg_map/map.h"
#include "fragg_map/planning/query_control.h"

namespace fragg::planning {

struct ClusterOptions {
  uint64_t min_cells = 8;     ///< >= 1; smaller components are dropped
  double max_extent_m = 3.0;  ///< > 0: split wider pieces (bounding box edge); 0: never split
  /// Throws InvalidArgument for min_cells 0 or a negative or NaN extent.
  void validate() const;
};

struct FrontierCluster {
  uint64_t id = 0;
  std::vector<VoxelKey> cells;                           ///< sorted by frontierOrder
  Eigen::Vector3d centroid_m = Eigen::Vector3d::Zero();  ///< mean of the cell centres
  Eigen::Vector3d min_m = Eigen::Vector3d::Zero();       ///< bounds of the cells' cubes
  Eigen::Vector3d max_m = Eigen::Vector3d::Zero();
  /// Mean direction from the cells towards their unknown neighbours (unit; zero when the
  /// directions cancel).
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();
};

class FrontierClusterer {
 public:
  explicit FrontierClusterer(const ClusterOptions& options = {});

  /// Clusters of `cells` (frontier cells of `map`), ordered by their first cell (frontierOrder).
  /// Ids carry over from the previous call for clusters with exactly the same cells; new
  /// clusters get ids never used before.
  /// `control`: a deadline or a cancel flag (QueryStopped is thrown when either comes; the
  /// ids given so far are kept).
  std::vector<FrontierCluster> cluster(const Map& map, const std::vector<VoxelKey>& cells,
                                       const QueryControl* control = nullptr);

 private:
  ClusterOptions options_;
  uint64_t next_id_ = 1;
  /// Hash of a previous cluster's cells -> its id.
  std::unordered_map<uint64_t, uint64_t> previous_;
};

}  // namespace fragg::planning
