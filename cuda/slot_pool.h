// The device pool of block slots (cells, keys, scan scratch, residency flags) and the host's
// mirror of its free stack. Grows by reallocating and copying on the stream.
#pragma once

#include <cstdint>
#include <vector>

#include "device_memory.h"
#include "device_types.h"

namespace fragg::cuda {

class SlotPool {
 public:
  /// Bytes a slot takes on the device, everything included.
  static size_t bytesPerSlot();

  explicit SlotPool(cudaStream_t stream) : stream_(stream) {}

  /// Grows to `capacity` slots, keeping every slot's contents; the new slots go on the free
  /// stack. Throws CudaOutOfMemory when the device has no room (the pool is unchanged).
  void grow(int32_t capacity);
  /// Every slot free, scratch clear (after the host map was changed directly).
  void clear();

  SlotArrays arrays() const;
  int32_t capacity() const { return capacity_; }
  size_t deviceBytes() const { return size_t(capacity_) * bytesPerSlot(); }

  // Host mirror of the free stack: slots [0, free_top) are free.
  int32_t freeTop() const { return free_top_; }
  /// Takes `n` slots off the stack (host-side allocation, for uploads).
  std::vector<int32_t> pop(int32_t n);
  /// The device allocated the slots above `new_top`; returns them.
  std::vector<int32_t> takenByDevice(int32_t new_top);
  /// Puts slots back on the stack, on the host and the device.
  void push(const std::vector<int32_t>& slots);

  /// Host mirror of the resident flags; uploadResident() sends it.
  std::vector<uint8_t>& residentHost() { return resident_host_; }
  void uploadResident();

 private:
  cudaStream_t stream_;
  int32_t capacity_ = 0;
  DeviceArray<Block> cells_;
  DeviceArray<BlockKey> keys_;
  DeviceArray<SlotScratch> scratch_;
  DeviceArray<int32_t> touched_list_;
  DeviceArray<uint8_t> fresh_;
  DeviceArray<uint8_t> dirty_;
  DeviceArray<uint32_t> last_used_;
  DeviceArray<uint64_t> changed_at_;
  DeviceArray<uint64_t> occupied_at_;
  DeviceArray<CullMemory> cull_;
  DeviceArray<int32_t> free_stack_;
  DeviceArray<uint8_t> resident_;
  std::vector<int32_t> free_host_;
  int32_t free_top_ = 0;
  std::vector<uint8_t> resident_host_;
};

}  // namespace fragg::cuda
