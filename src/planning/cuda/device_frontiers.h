// The frontier tracker's state on the map's device (planning's CUDA part): per slot of the
// CUDA backend's pool, the masks the tracker last saw and the frontier bits it found, kept in
// a DeviceScratch of the tracker's own. An update compares every slot of the map's device layer
// view with what the tracker saw (a slot read costs nothing next to a host round trip), lists
// the neighbourhoods that changed and examines them there; only the cell count comes back. The
// cells come back on demand (download). No CUDA header: frontier_tracker.cpp calls it in CUDA
// builds only (FRAGG_HAVE_CUDA).
#pragma once

#include <cstdint>
#include <vector>

#include "../frontier_masks.h"
#include "fragg_map/device_layer_view.h"
#include "fragg_map/device_scratch.h"
#include "fragg_map/planning/frontier_cells.h"

namespace fragg::planning {

/// What one device update did.
struct DeviceFrontierUpdate {
  int64_t delta = 0;      ///< change of the frontier cell count
  uint64_t changed = 0;   ///< slots whose masks differed from the tracker's (or whose block left)
  uint64_t examined = 0;  ///< blocks whose frontier cells were recomputed
  double compare_seconds = 0.0, examine_seconds = 0.0;
};

class DeviceFrontiers {
 public:
  /// The state for `filter` (its box and height tests; InvalidArgument for the obstacle
  /// distance filter, which reads cells: the host tracker's) on CUDA device `device`.
  DeviceFrontiers(const FrontierFilter& filter, int device);

  /// Brings the state up to date with `view` (the whole map's device layer view, held by the
  /// caller's lease) at `resolution_m`; with the filter's box, [box_lo, box_hi] are the blocks
  /// it reaches (the host tracker's range). `full`: forget what was seen first (also done when
  /// the view's pool changed size). CudaOutOfMemory when the state does not fit.
  DeviceFrontierUpdate update(const DeviceLayerView& view, double resolution_m,
                              const BlockKey& box_lo, const BlockKey& box_hi, bool full);

  /// Every block with frontier cells and its bits, in unspecified order.
  void download(std::vector<BlockKey>* keys, std::vector<FrontierBits>* bits);

  /// The CUDA device the state lives on.
  [[nodiscard]] int device() const;

 private:
  FrontierFilter filter_;
  std::unique_ptr<DeviceScratch> scratch_;
  int32_t slots_ = 0;  ///< pool slots the state is sized for (0: none yet)
  uint32_t update_number_ = 0;
};

}  // namespace fragg::planning
