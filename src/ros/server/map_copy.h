// Copies of the map for long readers (a .bt save, the GetOctomap services): taken under the
// map's read lock, read without it, so that insertion waits for the copy only.
#pragma once

#include "fragg_map/map.h"

namespace fragg::ros {

/// Every observed cell of `map` (its resident blocks on a paged map) in a new CPU map of the
/// same resolution and occupancy model (Map::extract over the observed key bounds; exact
/// cells; an empty map gives an empty copy). Hold the map's read lock.
[[nodiscard]] fragg::Map observedCopy(const fragg::Map& map);

}  // namespace fragg::ros
