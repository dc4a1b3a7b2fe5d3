// Dynamic hits of a scan on the CPU (MapParams::dynamic): classified against the host map as it
// is before the scan, then turned into free-only rays; and the surround test that makes cells
// void (DESIGN §12).
#pragma once

#include <cstdint>
#include <vector>

#include "fragg_map/block_map.h"
#include "fragg_map/dynamic_rule.h"
#include "fragg_map/internal/prepared_scan.h"
#include "fragg_map/internal/scan_scratch.h"

namespace fragg {

/// Whether a hit in cell `end` is dynamic under `rule` in `blocks`. kPassThrough: the cell is
/// void and every cell within rule.known_radius_cells of it (Chebyshev) is observed.
/// kSurround: the cell is void, or free with confidence with every such neighbour too. Blocks
/// the map lacks (never observed, or paged out) read as unobserved.
[[nodiscard]] bool isDynamicHit(const VoxelKey& end, const BlockMap& blocks,
                                const DynamicRule& rule);

/// Classifies every hit of `scan` (isDynamicHit on its end cell) and makes the dynamic ones
/// free-only (RayEnd::hit = 0). `dynamic_rays`: the indices of those rays in scan.rays,
/// ascending. Reads `blocks` only; `threads` workers (OpenMP).
void classifyDynamicHits(PreparedScan& scan, const BlockMap& blocks, const DynamicRule& rule,
                         int threads, std::vector<uint32_t>& dynamic_rays);

/// The pass-through rule (VoidSpaceRule::kPassThrough): a ray that passes through an occupied
/// cell (marked free, not hit, by this scan) whose neighbourhood within
/// rule.known_radius_cells has been observed shows that what was there has moved: the cell
/// becomes void (log-odds rule.seen_free_at_or_below_fx) instead of taking one miss. A static
/// surface keeps unobserved cells behind it (the ground's below it, a wall's inside it), so its
/// cells do not qualify. `free_marks`/`hit_marks`: the scan's marks of the block `key` (8 words
/// each); `resets` gets the cells to make void (8 words, bit c = cell index c), read from
/// `blocks` as they are before the scan.
void passThroughResets(const BlockKey& key, const uint64_t* free_marks, const uint64_t* hit_marks,
                       const BlockMap& blocks, const DynamicRule& rule, uint64_t* resets);

/// The surround test (VoidSpaceRule::kSurround), DUFOMap's rule for void space: a cell this scan's
/// rays passed through (none ended there) becomes void when every cell within
/// rule.known_radius_cells of it (Chebyshev) is seen free: ended in by none of this scan's rays,
/// and passed through by it or known (occupied or free) in `blocks` before the scan (an occupied
/// cell left by earlier hits of a mover does not keep its neighbours from becoming void). A static
/// surface always has a neighbour that is hit or never seen (the ground's cells below it, a
/// wall's inside, a pole's next cell), so grazing rays do not make it void; what stood in space
/// seen all around has moved. `marks`:
/// the scan's merged marks; `surrounded` gets 8 words per block of marks.touched() order (bit c =
/// cell index c), read from `blocks` as they are before the scan; `threads` workers (OpenMP).
void surroundedCells(const ScanScratch& marks, const BlockMap& blocks, const DynamicRule& rule,
                     int threads, std::vector<uint64_t>& surrounded);

}  // namespace fragg
