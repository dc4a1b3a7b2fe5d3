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

/// Whether every cell within rule.known_radius_cells of `v` (Chebyshev, `v` included) has been
/// observed in `blocks`.
[[nodiscard]] bool neighbourhoodObserved(const VoxelKey& v, const BlockMap& blocks,
                                         const DynamicRule& rule);

/// The pass-through rule: a ray that passes through an occupied cell (marked free, not hit, by
/// this scan) whose neighbourhood has been observed (neighbourhoodObserved) shows that what
/// was there has moved: the cell becomes void (log-odds rule.void_at_or_below_fx) instead of
/// taking one miss. A static surface keeps unobserved cells behind it (the ground's below it,
/// a wall's inside it), so its cells do not qualify. `free_marks`/`hit_marks`: the scan's
/// marks of the block `key` (8 words each); `resets` gets the cells to make void (8 words,
/// bit c = cell index c), read from `blocks` as they are before the scan.
void passThroughResets(const BlockKey& key, const uint64_t* free_marks, const uint64_t* hit_marks,
                       const BlockMap& blocks, const DynamicRule& rule, uint64_t* resets);

}  // namespace fragg
