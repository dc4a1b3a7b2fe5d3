#include "layer_view.h"

#include "cuda_stream.h"
#include "fragg_map/internal/reserve_headroom.h"

namespace fragg::cuda {

namespace {

/// Table entries for n keys: a power of two, at most half full.
uint32_t tableSizeFor(int64_t n) {
  uint32_t size = 1024;
  while (size < uint64_t(2 * n)) size *= 2;
  return size;
}

}  // namespace

DeviceLayerView LayerViews::build(const DeviceBlockCache& cache, uint64_t revision) {
  FRAGG_CUDA_CHECK(cudaSetDevice(device_));
  const SlotArrays slots = cache.arrays();
  const uint32_t entries = tableSizeFor(slots.capacity);
  table_.reserve(entries);
  FRAGG_CUDA_CHECK(cudaMemsetAsync(table_.get(), 0xff, entries * sizeof(int32_t), stream_));
  launchViewTable(slots, table_.get(), entries - 1, stream_);
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));  // readers use their own streams
  DeviceLayerView v;
  v.table = table_.get();
  v.table_mask = entries - 1;
  v.slot_keys = slots.keys;
  v.cells = slots.cells;
  v.masks = slots.masks;
  v.slots = slots.capacity;
  v.device = device_;
  v.revision = revision;
  return v;
}

void LayerViews::masksChangedSince(const DeviceBlockCache& cache, uint64_t revision,
                                   std::vector<BlockKey>* keys,
                                   std::vector<BlockStateMasks>* masks) {
  keys->clear();
  masks->clear();
  const SlotArrays slots = cache.arrays();
  if (slots.capacity == 0) return;
  FRAGG_CUDA_CHECK(cudaSetDevice(device_));
  changed_slots_.reserve(size_t(slots.capacity));
  count_.reserve(1);
  count_host_.reserve(1);
  FRAGG_CUDA_CHECK(cudaMemsetAsync(count_.get(), 0, sizeof(uint32_t), stream_));
  launchChangedSlots(slots, revision, changed_slots_.get(), count_.get(), stream_);
  copyToHost(count_host_.get(), count_.get(), 1, stream_);
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
  const uint32_t n = count_host_[0];
  if (n == 0) return;
  changed_keys_.reserve(n);
  changed_masks_.reserve(n);
  launchGatherMasks(slots, changed_slots_.get(), n, changed_keys_.get(), changed_masks_.get(),
                    stream_);
  reserveWithHeadroom(keys, n);
  reserveWithHeadroom(masks, n);
  keys->resize(n);
  masks->resize(n);
  copyToHost(keys->data(), changed_keys_.get(), n, stream_);
  copyToHost(masks->data(), changed_masks_.get(), n, stream_);
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
}

}  // namespace fragg::cuda
