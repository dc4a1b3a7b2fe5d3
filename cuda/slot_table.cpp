#include "slot_table.h"

#include <algorithm>
#include <string>

#include "fragg_map/errors.h"

namespace fragg::cuda {

void SlotTable::grow(int32_t capacity) {
  const int32_t old = this->capacity();
  if (capacity <= old) return;
  free_.resize(size_t(capacity));
  resident_.resize(size_t(capacity), 0);
  block_of_slot_.resize(size_t(capacity), kNoBlock);
  std::vector<int32_t> fresh;
  fresh.reserve(size_t(capacity - old));
  for (int32_t s = capacity - 1; s >= old; --s) fresh.push_back(s);
  push(fresh);
}

void SlotTable::clear() {
  const int32_t n = capacity();
  std::fill(resident_.begin(), resident_.end(), 0);
  std::fill(block_of_slot_.begin(), block_of_slot_.end(), kNoBlock);
  slot_of_block_.clear();
  device_only_ = 0;
  free_top_ = 0;
  for (int32_t s = n - 1; s >= 0; --s) free_[size_t(free_top_++)] = s;
}

std::vector<int32_t> SlotTable::pop(int32_t n) {
  if (n < 0 || n > free_top_)
    throw CudaError("slot pool has " + std::to_string(free_top_) + " free slots, " +
                    std::to_string(n) + " asked for (residency bug)");
  std::vector<int32_t> out(free_.begin() + (free_top_ - n), free_.begin() + free_top_);
  free_top_ -= n;
  return out;
}

std::vector<int32_t> SlotTable::takenByDevice(int32_t new_top) {
  new_top = std::max(new_top, 0);
  std::vector<int32_t> out;
  if (new_top >= free_top_) return out;
  out.assign(free_.begin() + new_top, free_.begin() + free_top_);
  free_top_ = new_top;
  for (int32_t s : out) bind(s, kNoBlock);
  return out;
}

void SlotTable::push(const std::vector<int32_t>& slots) {
  if (size_t(free_top_) + slots.size() > free_.size())
    throw CudaError("slot pool free stack overflow (a slot released twice: residency bug)");
  std::copy(slots.begin(), slots.end(), free_.begin() + free_top_);
  free_top_ += static_cast<int32_t>(slots.size());
}

bool SlotTable::deviceOnly(int32_t slot) const {
  return resident_[slot] != 0 && block_of_slot_[slot] == kNoBlock;
}

void SlotTable::bind(int32_t slot, BlockIndex block) {
  device_only_ += (block == kNoBlock ? 1 : 0) - (deviceOnly(slot) ? 1 : 0);
  resident_[slot] = 1;
  block_of_slot_[slot] = block;
  if (block != kNoBlock) setSlotOf(block, slot);
}

BlockIndex SlotTable::unbind(int32_t slot) {
  const BlockIndex block = block_of_slot_[slot];
  if (deviceOnly(slot)) --device_only_;
  resident_[slot] = 0;
  block_of_slot_[slot] = kNoBlock;
  if (block != kNoBlock) setSlotOf(block, -1);
  return block;
}

void SlotTable::setSlotOf(BlockIndex block, int32_t slot) {
  if (block >= slot_of_block_.size()) slot_of_block_.resize(size_t(block) + 1 + block / 2, -1);
  slot_of_block_[block] = slot;
}

std::vector<int32_t> leastRecentlyUsed(const SlotTable& table, const uint32_t* last_used,
                                       uint32_t current_scan, size_t n) {
  std::vector<int32_t> candidates;
  for (int32_t s = 0; s < table.capacity(); ++s)
    if (table.resident(s) && last_used[s] != current_scan) candidates.push_back(s);
  const size_t k = std::min(candidates.size(), n);
  std::partial_sort(candidates.begin(), candidates.begin() + k, candidates.end(),
                    [&](int32_t x, int32_t y) { return last_used[x] < last_used[y]; });
  candidates.resize(k);
  return candidates;
}

}  // namespace fragg::cuda
