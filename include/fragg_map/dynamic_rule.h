// The dynamic-scene rule (MapParams::dynamic) in the form both backends evaluate: plain data
// and __host__ __device__ tests, so that the CPU update and the CUDA kernels classify the same
// hits and make the same cells void.
#pragma once

#include <cstdint>

#include "fragg_map/cell.h"
#include "fragg_map/hd.h"

namespace fragg {

struct DynamicParams;
struct OccupancyParams;

/// Under VoidSpaceRule::kPassThrough (main's rule) a cell is void when observed and at or
/// below seen_free_at_or_below_fx (dynamic.void_probability). Under kSurround void cells sit
/// exactly at the lower clamp (log-odds occupancy.clamp_min): only the surround test takes a
/// cell there; an ordinary miss stops one unit (1/1024) above it. A neighbour counts as seen
/// free when no ray of this scan ended there and the scan passed through it or it was known
/// (occupied or free in the state masks) before the scan: only unknown space and the scan's own
/// hits keep a cell from becoming void, as DUFOMap's unknown inflation does.
struct DynamicRule {
  bool enabled = false;
  bool surround = false;                 ///< VoidSpaceRule::kSurround (else kPassThrough)
  int16_t void_fx = 0;                   ///< kSurround: the log-odds of a void cell (lower clamp)
  int16_t seen_free_at_or_below_fx = 0;  ///< confident free space (dynamic.void_probability)
  int known_radius_cells = 2;            ///< the neighbourhood's Chebyshev radius

  /// From the map's (validated) parameters.
  static DynamicRule fromParams(const DynamicParams& p, const OccupancyParams& occupancy);

  /// Whether a cell is void: hits there are dynamic (kPassThrough: when its neighbourhood has
  /// been observed too).
  [[nodiscard]] FRAGG_HD bool isVoid(const Cell& c) const {
    if (!surround) return c.observed() && c.log_odds_fx <= seen_free_at_or_below_fx;
    return c.observed() && c.log_odds_fx == void_fx;
  }
  /// Whether a cell counted as free with confidence before the scan.
  [[nodiscard]] FRAGG_HD bool seenFreeBefore(const Cell& c) const {
    return c.observed() && c.log_odds_fx <= seen_free_at_or_below_fx;
  }
  /// kSurround: the log-odds a miss leaves in a cell that was `before` and is `updated_fx`
  /// after the ordinary update: void when the surround test passed, else never void by misses
  /// alone (one unit above the clamp) unless it was void already.
  [[nodiscard]] FRAGG_HD int16_t afterMiss(const Cell& before, int16_t updated_fx,
                                           bool surrounded) const {
    if (surrounded) return void_fx;
    if (!isVoid(before) && updated_fx <= void_fx) return static_cast<int16_t>(void_fx + 1);
    return updated_fx;
  }
};

}  // namespace fragg
