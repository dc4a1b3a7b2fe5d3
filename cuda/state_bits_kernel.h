// Launcher of the cell-state bitmap kernel (state_bits_kernel.cu).
#pragma once

#include <cuda_runtime.h>

#include "fragg_map/cell.h"
#include "fragg_map/occupancy.h"

namespace fragg::cuda {

/// Launcher (state_bits_kernel.cu): slot -1 = a missing block (all unknown).
void launchCellStateBits(const Block* slot_cells, const int32_t* slots, uint32_t n,
                         const OccupancyModel& model, uint64_t* out, cudaStream_t stream);

}  // namespace fragg::cuda
