// Cell-state bitmaps over the device block cache (MapBackend::cellStateBits): the blocks are
// made resident, one warp per block reads its slot and writes 8 words of free cells and 8 of
// unknown cells (bit i = cell index i). The frontier tracker's per-block masks.
#pragma once

#include <cuda_runtime.h>

#include <vector>

#include "cuda_array.h"
#include "device_block_cache.h"
#include "fragg_map/occupancy.h"
#include "state_bits_kernel.h"

namespace fragg::cuda {

class CellStateBits {
 public:
  explicit CellStateBits(cudaStream_t stream) : stream_(stream) {}
  /// 16 words per key into `out` (see MapBackend::cellStateBits).
  void compute(DeviceBlockCache& cache, const std::vector<BlockKey>& keys,
               const OccupancyModel& model, BlockMap& blocks, uint64_t* out);

 private:
  cudaStream_t stream_;
  PinnedArray<int32_t> slots_host_;
  DeviceArray<int32_t> slots_;
  DeviceArray<uint64_t> bits_;
};

}  // namespace fragg::cuda
