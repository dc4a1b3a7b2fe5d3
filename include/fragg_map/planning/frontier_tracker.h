// Incremental frontier cells: after each scan only the blocks changed since the last update
// (Map::changedBlocksSince) and their 26 neighbour blocks are examined again; the set always
// equals findFrontierCells() on the same map and filter. A map whose blocks left or joined its
// view since the last update (clearBox, truncate, reset, paging: Map::viewEpoch), or another
// map, is recomputed in full. On a paged map only resident blocks are seen: page the region of
// interest in first (Map::ensureResident).
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "fragg_map/planning/frontier_cells.h"

namespace fragg::planning {

struct FrontierUpdateStats {
  bool full = false;             ///< recomputed every block
  uint64_t blocks_examined = 0;  ///< blocks whose frontier cells were recomputed
  uint64_t cells = 0;            ///< frontier cells after the update
  double seconds = 0.0;
};

class FrontierTracker {
 public:
  /// Throws InvalidArgument for a bad filter or negative thread count.
  explicit FrontierTracker(const FrontierFilter& filter = {}, int threads = 0);

  /// Brings the set up to date with `map` (hold its read lock).
  FrontierUpdateStats update(const Map& map);
  /// Forgets everything: the next update is a full one.
  void reset();

  /// The frontier cells, sorted by frontierOrder.
  std::vector<VoxelKey> cells() const;
  uint64_t size() const { return total_; }
  /// The map revision the set belongs to.
  uint64_t revision() const { return revision_; }
  const FrontierFilter& filter() const { return filter_; }

 private:
  /// Recomputes the listed blocks (parallel); blocks left without frontier cells are dropped.
  void recompute(const Map& map, const BlockView& view, const std::vector<BlockKey>& blocks);

  FrontierFilter filter_;
  int threads_;
  bool valid_ = false;
  uint64_t revision_ = 0;
  uint64_t epoch_ = 0;  ///< Map::viewEpoch() at the last update
  uint64_t total_ = 0;
  /// Frontier cells per block (cell indices, increasing).
  std::unordered_map<BlockKey, std::vector<uint16_t>, BlockKeyHash> by_block_;
};

}  // namespace fragg::planning
