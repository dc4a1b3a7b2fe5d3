// Agreement between two maps of the same resolution, cell by cell (same voxel key).
//
// A cell is *known* in a map when its state is free or occupied:
//  * own band (default): the state from the map's own occupancy model, so a cell that was
//    never observed, or whose probability lies within the unknown band, is unknown;
//  * OctoMap threshold: every observed cell is known, occupied iff log-odds >= 0
//    (p >= 0.5, OctoMap's isNodeOccupied and what a .bt file stores), free otherwise.
#pragma once

#include <cstdint>

#include "fragg_map/map.h"

namespace fragg {

struct CompareOptions {
  bool octomap_threshold = false;  ///< OctoMap's rule instead of each map's own band
};

struct MapComparison {
  /// confusion[state in a][state in b], indexed by CellState (unknown, free, occupied), over
  /// every cell observed in at least one of the maps (cells observed in neither are not
  /// counted).
  uint64_t confusion[3][3] = {};
  uint64_t known_in_a = 0;
  uint64_t known_in_b = 0;
  uint64_t known_in_both = 0;    ///< known in a and known in b
  uint64_t known_in_either = 0;  ///< known in a or known in b
  uint64_t agreeing = 0;         ///< known in both with the same state
  bool octomap_threshold = false;

  uint64_t count(CellState a, CellState b) const {
    return confusion[static_cast<int>(a)][static_cast<int>(b)];
  }
  /// agreeing / known_in_both: agreement where both maps know the cell. NaN when none is.
  double agreementInBoth() const;
  /// agreeing / known_in_either: a cell known in one map and unknown in the other counts as
  /// a disagreement. NaN when no cell is known in either map.
  double agreementInEither() const;
};

/// Compares `a` and `b` cell by cell. Resolutions must agree to 1e-5 (relative: OctoMap
/// files carry 6 significant digits), else InvalidArgument.
MapComparison compareMaps(const Map& a, const Map& b,
                          const CompareOptions& options = CompareOptions());

}  // namespace fragg
