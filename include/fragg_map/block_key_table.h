// A flat open-addressing table from block keys to 32-bit indices: the host map's block index
// (BlockMap) and the planning tier's per-block records. Linear probing over one array of
// 16-byte slots (key and value side by side: a lookup is one or two cache lines, where a node
// table chases a pointer per entry, and after paging has erased and re-created millions of
// blocks those nodes lie all over the heap: in W4's paged build, std::unordered_map's lookups
// drew 8x the profile samples they drew in the in-memory build). Erasure shifts the following
// entries back (no tombstones), so
// lookups stay short however many keys come and go; the table keeps its largest capacity.
// Lookups may run on many threads while nothing is added or erased.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "fragg_map/key.h"

namespace fragg {

class BlockKeyTable {
 public:
  static constexpr uint32_t kNone = UINT32_MAX;

  BlockKeyTable() = default;
  BlockKeyTable(const BlockKeyTable&) = default;
  BlockKeyTable& operator=(const BlockKeyTable&) = default;
  BlockKeyTable(BlockKeyTable&& o) noexcept { *this = std::move(o); }
  BlockKeyTable& operator=(BlockKeyTable&& o) noexcept {
    slots_ = std::move(o.slots_);
    mask_ = o.mask_;
    size_ = o.size_;
    o.slots_.clear();
    o.mask_ = o.size_ = 0;
    return *this;
  }

  /// The value of `key`, or kNone.
  uint32_t find(const BlockKey& key) const {
    if (slots_.empty()) return kNone;
    for (size_t i = home(key);; i = (i + 1) & mask_) {
      const Slot& s = slots_[i];
      if (s.value == kNone) return kNone;
      if (s.key == key) return s.value;
    }
  }
  /// Adds `key` -> `value` (`value` is not kNone; the key must not be present).
  void insert(const BlockKey& key, uint32_t value) {
    if (2 * (size_ + 1) > slots_.size()) rehash(capacityFor(size_ + 1));
    place(key, value);
    ++size_;
  }
  /// Removes `key`; false when it was not there.
  bool erase(const BlockKey& key) {
    if (slots_.empty()) return false;
    size_t i = home(key);
    for (;; i = (i + 1) & mask_) {
      if (slots_[i].value == kNone) return false;
      if (slots_[i].key == key) break;
    }
    // Backward shift: an entry after the hole moves into it when its home is not between the
    // hole and itself (it stays reachable from its home without crossing an empty slot).
    for (size_t j = (i + 1) & mask_; slots_[j].value != kNone; j = (j + 1) & mask_) {
      const size_t from_home = (j - home(slots_[j].key)) & mask_;
      if (from_home >= ((j - i) & mask_)) {
        slots_[i] = slots_[j];
        i = j;
      }
    }
    slots_[i].value = kNone;
    --size_;
    return true;
  }
  /// Makes room for `n` keys in all without growing.
  void reserve(size_t n) {
    if (2 * n > slots_.size()) rehash(capacityFor(n));
  }
  /// Empties the table and hands its memory back.
  void clear() {
    std::vector<Slot>().swap(slots_);
    size_ = 0;
    mask_ = 0;
  }
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  /// Memory of the slots.
  size_t bytes() const { return slots_.capacity() * sizeof(Slot); }
  /// fn(key, value) for every entry, in slot order (deterministic for a given history).
  template <class Fn>
  void forEach(Fn&& fn) const {
    for (const Slot& s : slots_)
      if (s.value != kNone) fn(s.key, s.value);
  }

 private:
  struct Slot {
    BlockKey key;
    uint32_t value = kNone;
  };
  static_assert(sizeof(Slot) == 16, "a slot is a key and a value");

  size_t home(const BlockKey& key) const { return BlockKeyHash()(key) & mask_; }
  static size_t capacityFor(size_t n) {
    size_t c = 64;
    while (c < 2 * n) c *= 2;
    return c;
  }
  void place(const BlockKey& key, uint32_t value) {
    size_t i = home(key);
    while (slots_[i].value != kNone) i = (i + 1) & mask_;
    slots_[i].key = key;
    slots_[i].value = value;
  }
  void rehash(size_t capacity) {
    std::vector<Slot> old(capacity);
    old.swap(slots_);
    mask_ = capacity - 1;
    for (const Slot& s : old)
      if (s.value != kNone) place(s.key, s.value);
  }

  std::vector<Slot> slots_;
  size_t mask_ = 0;
  size_t size_ = 0;
};

}  // namespace fragg
