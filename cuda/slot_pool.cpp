#include "slot_pool.h"

#include <algorithm>
#include <string>

#include "cuda_stream.h"
#include "kernels.h"

namespace fragg::cuda {

namespace {
/// Reallocates `a` to `n` elements, copying the first `keep` on the stream and zeroing the
/// rest. The new array is allocated before the old one is freed.
template <class T>
void regrow(DeviceArray<T>& a, size_t keep, size_t n, cudaStream_t s) {
  DeviceArray<T> bigger(n);
  if (keep)
    FRAGG_CUDA_CHECK(
        cudaMemcpyAsync(bigger.get(), a.get(), keep * sizeof(T), cudaMemcpyDeviceToDevice, s));
  if (n > keep)
    FRAGG_CUDA_CHECK(cudaMemsetAsync(bigger.get() + keep, 0, (n - keep) * sizeof(T), s));
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(s));  // the old array may go now
  a = std::move(bigger);
}
}  // namespace

size_t SlotPool::bytesPerSlot() {
  return sizeof(Block) + sizeof(BlockStateMasks) + sizeof(BlockKey) + sizeof(SlotScratch) +
         sizeof(int32_t) + 2 * sizeof(uint8_t) + sizeof(uint32_t) + 3 * sizeof(uint64_t) +
         sizeof(CullMemory) + sizeof(int32_t) + 2 * sizeof(uint8_t);
}

void SlotPool::grow(int32_t capacity) {
  const int32_t old = this->capacity();
  if (capacity <= old) return;
  if (capacity > kMaxCapacity)
    throw CudaOutOfMemory("device block pool cannot grow to " + std::to_string(capacity) +
                          " slots (at most " + std::to_string(kMaxCapacity) + ")");
  // Check the room first, so that a failure leaves every array as it was.
  size_t free_bytes = 0, total_bytes = 0;
  FRAGG_CUDA_CHECK(cudaMemGetInfo(&free_bytes, &total_bytes));
  const size_t need = size_t(capacity) * bytesPerSlot() + (64u << 20);
  if (need > free_bytes)
    throw CudaOutOfMemory("device block pool cannot grow to " + std::to_string(capacity) +
                          " slots (" + std::to_string(need >> 20) + " MiB needed, " +
                          std::to_string(free_bytes >> 20) + " MiB free)");
  const size_t keep = size_t(old), n = size_t(capacity);
  regrow(cells_, keep, n, stream_);
  regrow(masks_, keep, n, stream_);
  regrow(keys_, keep, n, stream_);
  regrow(scratch_, keep, n, stream_);
  regrow(touched_list_, keep, n, stream_);
  regrow(fresh_, keep, n, stream_);
  regrow(dirty_, keep, n, stream_);
  regrow(last_used_, keep, n, stream_);
  regrow(changed_at_, keep, n, stream_);
  regrow(occupied_at_, keep, n, stream_);
  regrow(masks_at_, keep, n, stream_);
  regrow(cull_, keep, n, stream_);
  regrow(free_stack_, size_t(table_.freeCount()), n, stream_);
  regrow(resident_, keep, n, stream_);
  regrow(free_saturated_, keep, n, stream_);
  const int32_t top = table_.freeCount();
  table_.grow(capacity);
  uploadFreeStack(top);
}

void SlotPool::clear() {
  if (capacity() == 0) return;
  const size_t n = size_t(capacity());
  FRAGG_CUDA_CHECK(cudaMemsetAsync(scratch_.get(), 0, n * sizeof(SlotScratch), stream_));
  FRAGG_CUDA_CHECK(cudaMemsetAsync(fresh_.get(), 0, n, stream_));
  FRAGG_CUDA_CHECK(cudaMemsetAsync(dirty_.get(), 0, n, stream_));
  FRAGG_CUDA_CHECK(cudaMemsetAsync(resident_.get(), 0, n, stream_));
  FRAGG_CUDA_CHECK(cudaMemsetAsync(free_saturated_.get(), 0, n, stream_));
  table_.clear();
  uploadFreeStack(0);
}

SlotArrays SlotPool::arrays() const {
  SlotArrays a;
  a.cells = cells_.get();
  a.masks = masks_.get();
  a.keys = keys_.get();
  a.scratch = scratch_.get();
  a.touched_list = touched_list_.get();
  a.fresh = fresh_.get();
  a.dirty = dirty_.get();
  a.last_used = last_used_.get();
  a.changed_at = changed_at_.get();
  a.occupied_at = occupied_at_.get();
  a.masks_at = masks_at_.get();
  a.cull = cull_.get();
  a.free_stack = free_stack_.get();
  a.resident = resident_.get();
  a.free_saturated = free_saturated_.get();
  a.capacity = capacity();
  return a;
}

std::vector<BlockIndex> SlotPool::release(const std::vector<int32_t>& slots) {
  std::vector<BlockIndex> blocks;
  if (slots.empty()) return blocks;
  blocks.reserve(slots.size());
  for (int32_t s : slots) blocks.push_back(table_.unbind(s));
  uploadResident();
  const int32_t top = table_.freeCount();
  table_.push(slots);
  uploadFreeStack(top);
  // A free slot is never marked saturated: a ray that takes it for a new block must not skip.
  launchClearSaturated(arrays(), free_stack_.get() + top, uint32_t(slots.size()), stream_);
  return blocks;
}

void SlotPool::uploadResident() {
  const std::vector<uint8_t>& flags = table_.residentFlags();
  copyToDevice(resident_.get(), flags.data(), flags.size(), stream_);
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
}

void SlotPool::uploadFreeStack(int32_t from) {
  const int32_t top = table_.freeCount();
  if (top <= from) return;
  copyToDevice(free_stack_.get() + from, table_.freeStack() + from, size_t(top - from), stream_);
  // The host vector is read by the copy: wait before it can change again.
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
}

}  // namespace fragg::cuda
