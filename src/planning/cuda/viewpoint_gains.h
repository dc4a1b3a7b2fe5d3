// Viewpoint gains on CUDA (planning's CUDA part): the gain walk over the map's device layer view,
// one thread a viewpoint and ray, in the map's device scratch. No CUDA header: the rest of
// planning calls it (viewpoints.cpp) in CUDA builds only.
#pragma once

#include "../gain_walk.h"
#include "fragg_map/device_layer_view.h"
#include "fragg_map/device_scratch.h"
#include "fragg_map/occupancy.h"

namespace fragg::planning {

/// One gain per viewpoint of `batch` into `out`. Every block the rays can reach must be in
/// `view` (Map::deviceView over the batch's reach). Throws InvalidArgument when one viewpoint's
/// cell bitmap would pass 4 GiB, CudaOutOfMemory when the scratch cannot grow.
/// `tables_seconds`/`walk_seconds`/`rounds` (all or none): the stages' times, with a stream
/// synchronisation between them.
void viewpointGainsOnDevice(const DeviceLayerView& view, DeviceScratch& scratch,
                            const GainBatch& batch, const OccupancyModel& model, double* out,
                            double* tables_seconds = nullptr, double* walk_seconds = nullptr,
                            size_t* rounds = nullptr);

/// The blocks a batch's rays can reach: [lo, hi] (inclusive).
void gainReach(const GainBatch& batch, BlockKey* lo, BlockKey* hi);

}  // namespace fragg::planning
