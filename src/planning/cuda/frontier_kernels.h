// The frontier tracker's device pass (frontier_kernels.cu): its state per slot of the map's
// device pool, the kernels' arguments and launchers. No host-only header here, so the .cu file
// compiles without Eigen.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>

#include "../frontier_masks.h"
#include "fragg_map/device_layer_view.h"

namespace fragg::cuda {

/// The box and height tests of a FrontierFilter (FrontierFilter::keepsCentre) and the block
/// range its box reaches, in plain numbers for a kernel.
struct FrontierKernelFilter {
  bool use_box = false;
  double box_min_m[3] = {0, 0, 0}, box_max_m[3] = {0, 0, 0};
  BlockKey box_lo, box_hi;  ///< blocks that can hold cells of the box
  bool use_height = false;
  double min_z_m = 0.0, max_z_m = 0.0;
  double resolution_m = 0.0;
};

/// The tracker's state per pool slot (each array `slots` long), on the view's device.
struct FrontierSlots {
  planning::StateMasks* seen = nullptr;    ///< the masks the tracker last saw at the slot
  BlockKey* keys = nullptr;                ///< the block they belong to
  uint8_t* valid = nullptr;                ///< 1 when seen/keys/bits/counts hold a block
  planning::FrontierBits* bits = nullptr;  ///< its frontier cells (after the filter)
  uint32_t* counts = nullptr;              ///< popcount of bits
  uint32_t* marks = nullptr;               ///< update number that listed it for examination
  int32_t* examine = nullptr;              ///< slots listed this update
  int32_t slots = 0;
};

/// Counters of one update, read back once.
struct FrontierCounters {
  unsigned long long delta;  ///< change of the frontier cell count (two's complement)
  uint32_t changed;          ///< slots whose masks differ from those the tracker saw (or left)
  uint32_t examined;         ///< slots listed for examination
};

/// Compares every slot's masks in `view` with the tracker's, keeps the new ones, clears the
/// slots whose block left, and lists the blocks whose frontier cells may have changed
/// (frontier_masks.h: neighboursReached) in `state.examine`.
void launchFrontierCompare(const DeviceLayerView& view, const FrontierSlots& state,
                           const FrontierKernelFilter& filter, uint32_t update_number,
                           FrontierCounters* counters, cudaStream_t stream);
/// Recomputes the frontier bits of the `n` listed slots from the view's masks.
void launchFrontierExamine(const DeviceLayerView& view, const FrontierSlots& state,
                           const FrontierKernelFilter& filter, uint32_t n,
                           FrontierCounters* counters, cudaStream_t stream);
/// Copies the key and bits of every slot with frontier cells to `keys`/`bits` (`count`: how
/// many), in unspecified order.
void launchFrontierGather(const FrontierSlots& state, BlockKey* keys, planning::FrontierBits* bits,
                          uint32_t* count, cudaStream_t stream);

}  // namespace fragg::cuda
