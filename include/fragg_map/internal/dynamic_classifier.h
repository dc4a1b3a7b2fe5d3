// Dynamic hits of a scan on the CPU (MapParams::dynamic): classified against the host map as it
// is before the scan, then turned into free-only rays (DESIGN §12).
#pragma once

#include <cstdint>
#include <vector>

#include "fragg_map/block_map.h"
#include "fragg_map/dynamic_rule.h"
#include "fragg_map/internal/prepared_scan.h"

namespace fragg {

/// Whether a hit in cell `end` is dynamic under `rule` in `blocks`: the cell is void and every
/// cell within rule.known_radius_cells of it (Chebyshev) is observed. Blocks the map lacks
/// (never observed, or paged out) read as unobserved.
[[nodiscard]] bool isDynamicHit(const VoxelKey& end, const BlockMap& blocks,
                                const DynamicRule& rule);

/// Classifies every hit of `scan` (isDynamicHit on its end cell) and makes the dynamic ones
/// free-only (RayEnd::hit = 0). `dynamic_rays`: the indices of those rays in scan.rays,
/// ascending. Reads `blocks` only; `threads` workers (OpenMP).
void classifyDynamicHits(PreparedScan& scan, const BlockMap& blocks, const DynamicRule& rule,
                         int threads, std::vector<uint32_t>& dynamic_rays);

}  // namespace fragg
