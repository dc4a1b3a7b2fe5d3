// The host's book of the device block pool (no CUDA here, so it is unit-tested without a
// device): which slots are free (a stack mirrored on the device; the ray kernel pops from its
// top), which hold a block, and which host block each holds.
#pragma once

#include <cstdint>
#include <vector>

#include "fragg_map/block_map.h"

namespace fragg::cuda {

class SlotTable {
 public:
  /// Adds slots [capacity(), capacity) to the free stack (the highest at the bottom).
  void grow(int32_t capacity);
  /// Every slot free and bound to nothing.
  void clear();
  int32_t capacity() const { return static_cast<int32_t>(block_of_slot_.size()); }

  // The free stack: slots [0, freeCount()) of freeStack() are free; the top is the end.
  int32_t freeCount() const { return free_top_; }
  const int32_t* freeStack() const { return free_.data(); }
  /// Takes `n` slots off the top (host-side allocation). Throws CudaError when fewer are
  /// free (the caller makes room first: a shortfall is a residency bug).
  std::vector<int32_t> pop(int32_t n);
  /// The device popped the stack down to `new_top` (ray-side allocation): returns the slots it
  /// took, bound to no host block yet (resident, device-only).
  std::vector<int32_t> takenByDevice(int32_t new_top);
  /// Puts released slots back on the stack.
  void push(const std::vector<int32_t>& slots);

  // Residency.
  bool resident(int32_t slot) const { return resident_[slot] != 0; }
  const std::vector<uint8_t>& residentFlags() const { return resident_; }
  /// The slot holds host block `block` (kNoBlock: a block that exists on the device only).
  void bind(int32_t slot, BlockIndex block);
  /// The slot holds nothing any more (not pushed: see push()). Returns the host block it held.
  BlockIndex unbind(int32_t slot);
  /// kNoBlock when the slot is free or its block exists on the device only.
  BlockIndex blockOf(int32_t slot) const { return block_of_slot_[slot]; }
  /// Resident slots bound to no host block (blocks the device created since they were last
  /// written back).
  int32_t deviceOnlyCount() const { return device_only_; }
  /// -1 when the host block has no slot.
  int32_t slotOf(BlockIndex block) const {
    return block < slot_of_block_.size() ? slot_of_block_[block] : -1;
  }

 private:
  void setSlotOf(BlockIndex block, int32_t slot);
  bool deviceOnly(int32_t slot) const;

  std::vector<int32_t> free_;
  int32_t free_top_ = 0;
  std::vector<uint8_t> resident_;
  std::vector<BlockIndex> block_of_slot_;
  std::vector<int32_t> slot_of_block_;  ///< by host block index
  int32_t device_only_ = 0;
};

/// The `n` resident slots used least recently (smallest `last_used`), never one used in scan
/// `current_scan`; fewer when there are not that many.
std::vector<int32_t> leastRecentlyUsed(const SlotTable& table, const uint32_t* last_used,
                                       uint32_t current_scan, size_t n);

}  // namespace fragg::cuda
