// A backend that integrates prepared scans into the host map (CPU) or its device cache (CUDA).
#pragma once

#include <cstdint>

#include "fragg_map/block_map.h"
#include "fragg_map/insert_stats.h"
#include "fragg_map/internal/prepared_scan.h"
#include "fragg_map/map_params.h"
#include "fragg_map/occupancy.h"

namespace fragg {

class Integrator {
 public:
  virtual ~Integrator() = default;
  /// Ray casts `scan` (each cell updated at most once, hit wins) and applies the updates to
  /// `blocks`, stamping changed blocks with `revision`. Fills the traversal counters of `stats`.
  virtual void integrate(const PreparedScan& scan, const OccupancyModel& model, RayCast raycast,
                         uint64_t revision, BlockMap& blocks, InsertStats& stats) = 0;
  virtual const char* name() const = 0;
};

}  // namespace fragg
