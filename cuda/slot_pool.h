// The device pool of block slots (cells, keys, scan scratch, residency flags) with the host's
// book of it (SlotTable). Grows by reallocating and copying on the stream.
#pragma once

#include <cstdint>
#include <vector>

#include "cuda_array.h"
#include "device_types.h"
#include "slot_table.h"

namespace fragg::cuda {

class SlotPool {
 public:
  /// Bytes a slot takes on the device, everything included.
  static size_t bytesPerSlot();
  /// Most slots a pool holds: a slot index must not reach the window entries' flag bit.
  static constexpr int32_t kMaxCapacity = kWindowSlotMask;

  explicit SlotPool(cudaStream_t stream) : stream_(stream) {}

  /// Grows to `capacity` slots, keeping every slot's contents; the new slots go on the free
  /// stack. Throws CudaOutOfMemory when the device has no room (the pool is unchanged).
  void grow(int32_t capacity);
  /// Every slot free, scratch clear (after the host map was changed directly).
  void clear();

  SlotArrays arrays() const;
  int32_t capacity() const { return table_.capacity(); }
  size_t deviceBytes() const { return size_t(capacity()) * bytesPerSlot(); }
  const SlotTable& table() const { return table_; }

  /// Takes `n` free slots for uploads (throws CudaError when fewer are free).
  std::vector<int32_t> pop(int32_t n) { return table_.pop(n); }
  /// The device allocated the slots above `new_top`: they become resident, device-only.
  std::vector<int32_t> takenByDevice(int32_t new_top) { return table_.takenByDevice(new_top); }
  void bind(int32_t slot, BlockIndex block) { table_.bind(slot, block); }
  /// Frees slots (host book and device stack, resident flags sent); returns their host blocks
  /// (kNoBlock for device-only ones).
  std::vector<BlockIndex> release(const std::vector<int32_t>& slots);
  /// Sends the host's resident flags to the device.
  void uploadResident();

 private:
  /// Sends the free stack's entries [from, top) to the device.
  void uploadFreeStack(int32_t from);

  cudaStream_t stream_;
  SlotTable table_;
  DeviceArray<Block> cells_;
  DeviceArray<BlockStateMasks> masks_;
  DeviceArray<BlockKey> keys_;
  DeviceArray<SlotScratch> scratch_;
  DeviceArray<int32_t> touched_list_;
  DeviceArray<uint8_t> fresh_;
  DeviceArray<uint8_t> dirty_;
  DeviceArray<uint32_t> last_used_;
  DeviceArray<uint64_t> changed_at_;
  DeviceArray<uint64_t> occupied_at_;
  DeviceArray<uint64_t> masks_at_;
  DeviceArray<CullMemory> cull_;
  DeviceArray<int32_t> free_stack_;
  DeviceArray<uint8_t> resident_;
  DeviceArray<uint8_t> free_saturated_;
};

}  // namespace fragg::cuda
