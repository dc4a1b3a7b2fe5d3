// The dynamic-scene rule (MapParams::dynamic) in the form both backends evaluate: plain data
// and __host__ __device__ tests, so that the CPU update and the CUDA kernels classify the same
// hits.
#pragma once

#include <cstdint>

#include "fragg_map/cell.h"
#include "fragg_map/hd.h"

namespace fragg {

struct DynamicParams;

struct DynamicRule {
  bool enabled = false;
  int16_t void_at_or_below_fx = 0;  ///< a cell is void at or below this log-odds
  int known_radius_cells = 2;

  /// From the map's (validated) parameters.
  static DynamicRule fromParams(const DynamicParams& p);

  /// Whether a cell is void: observed, and free with confidence.
  [[nodiscard]] FRAGG_HD bool isVoid(const Cell& c) const {
    return c.observed() && c.log_odds_fx <= void_at_or_below_fx;
  }
};

}  // namespace fragg
