// Viewpoint gains over the device block cache (MapBackend::viewpointGains): the blocks the
// rays can reach are made resident, a table from block keys to slots is built on the device
// from the pool, and one thread per (viewpoint, ray) walks the same DDA as the CPU code
// (internal/gain_walk.h), counting each unknown cell once per viewpoint through a bitmap of
// the cube the viewpoint's rays can reach.
#pragma once

#include <cuda_runtime.h>

#include "cuda_array.h"
#include "device_block_cache.h"
#include "fragg_map/internal/gain_walk.h"
#include "gain_kernels.h"

namespace fragg::cuda {

class ViewpointGains {
 public:
  explicit ViewpointGains(cudaStream_t stream) : stream_(stream) {}
  /// One gain per viewpoint into `out`. Throws CudaOutOfMemory when the pool cannot hold the
  /// blocks in reach, InvalidArgument when one viewpoint's bitmap would pass 4 GiB.
  void compute(DeviceBlockCache& cache, const GainBatch& batch, const OccupancyModel& model,
               BlockMap& blocks, double* out);

 private:
  cudaStream_t stream_;
  DeviceArray<unsigned long long> table_keys_, seen_;
  DeviceArray<int32_t> table_slots_;
  DeviceArray<double> origins_, cos_, sin_, rays_, gains_;
};

}  // namespace fragg::cuda
