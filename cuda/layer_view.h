// The read-only device layer view (fragg_map/device_layer_view.h) over the CUDA backend's block
// pool, and the changed-block list compacted on the device (DESIGN §12, issue 34 items 2-3):
// the core's two ways for readers to reach the layers the integrator keeps on the device.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>
#include <vector>

#include "cuda_array.h"
#include "device_block_cache.h"
#include "fragg_map/device_layer_view.h"

namespace fragg::cuda {

class LayerViews {
 public:
  LayerViews(cudaStream_t stream, int device) : stream_(stream), device_(device) {}

  /// The view over every block resident in `cache` (the key table built on the device), for
  /// map revision `revision`. The table is the view's: a second call rebuilds it in place.
  [[nodiscard]] DeviceLayerView build(const DeviceBlockCache& cache, uint64_t revision);

  /// Keys and state masks of the resident blocks whose masks changed after `revision`
  /// (SlotArrays::masks_at), in unspecified order: a compaction on the device, then the
  /// masks of just those blocks copied back.
  void masksChangedSince(const DeviceBlockCache& cache, uint64_t revision,
                         std::vector<BlockKey>* keys, std::vector<BlockStateMasks>* masks);

  size_t deviceBytes() const {
    return table_.bytes() + changed_slots_.bytes() + changed_keys_.bytes() +
           changed_masks_.bytes() + count_.bytes();
  }

 private:
  cudaStream_t stream_;
  int device_;
  DeviceArray<int32_t> table_;
  DeviceArray<int32_t> changed_slots_;
  DeviceArray<BlockKey> changed_keys_;
  DeviceArray<BlockStateMasks> changed_masks_;
  DeviceArray<uint32_t> count_;
  PinnedArray<uint32_t> count_host_;
};

/// Launchers (layer_view_kernels.cu).
void launchViewTable(const SlotArrays& slots, int32_t* table, uint32_t table_mask,
                     cudaStream_t stream);
void launchChangedSlots(const SlotArrays& slots, uint64_t revision, int32_t* out, uint32_t* count,
                        cudaStream_t stream);
void launchGatherMasks(const SlotArrays& slots, const int32_t* which, uint32_t n, BlockKey* keys,
                       BlockStateMasks* masks, cudaStream_t stream);

}  // namespace fragg::cuda
