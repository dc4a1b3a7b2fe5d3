// Viewpoint gains on CUDA (planning's CUDA part): the gain walk over the map's device layer view,
// by one of the GainKernel variants, in the map's device scratch. No CUDA header: the rest of
// planning calls it (viewpoints.cpp) in CUDA builds only.
#pragma once

#include "../gain_walk.h"
#include "fragg_map/device_layer_view.h"
#include "fragg_map/device_scratch.h"
#include "fragg_map/occupancy.h"
#include "fragg_map/planning/viewpoints.h"

namespace fragg::planning {

/// What a batch did on the device (viewpointGainsOnDevice with `stats`): the stages' times
/// (seconds, a stream synchronisation between them), the kernel launches, and for the pooled
/// kernels the most block bitmaps one round asked for and the viewpoints computed again by
/// the sized kernel because their round found the pool too small.
struct DeviceGainStats {
  double tables_seconds = 0.0, walk_seconds = 0.0;
  size_t rounds = 0, pool_blocks_wanted = 0, pool_reruns = 0;
};

/// One gain per viewpoint of `batch` into `out`, by the kernel `options` names. Every block
/// the rays can reach must be in `view` (Map::deviceView over the batch's reach). Throws
/// InvalidArgument when one viewpoint's cell bitmap would pass 4 GiB, CudaOutOfMemory when the
/// scratch cannot grow. `stats` (optional): the stages timed apart, and the counts.
void viewpointGainsOnDevice(const DeviceLayerView& view, DeviceScratch& scratch,
                            const GainBatch& batch, const OccupancyModel& model,
                            const GainDeviceOptions& options, double* out,
                            DeviceGainStats* stats = nullptr);

/// The blocks a batch's rays can reach: [lo, hi] (inclusive).
void gainReach(const GainBatch& batch, BlockKey* lo, BlockKey* hi);

}  // namespace fragg::planning
