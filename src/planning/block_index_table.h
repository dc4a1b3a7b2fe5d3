// A flat open-addressing table from block keys to indices (internal to fragg_map_planning):
// the frontier tracker's per-block records are found through it 27 times per examined block,
// so lookups are a few probes in two arrays. Keys are only added (a rebuild starts over);
// lookups may run on many threads while nothing is added.
#pragma once

#include <cstdint>
#include <vector>

#include "fragg_map/key.h"

namespace fragg::planning {

class BlockIndexTable {
 public:
  static constexpr uint32_t kNone = UINT32_MAX;

  void clear() {
    keys_.clear();
    values_.clear();
    size_ = 0;
  }
  /// Makes room for `n` keys without rehashing.
  void reserve(size_t n) {
    if (2 * n > keys_.size()) rehash(capacityFor(n));
  }
  /// The index of `key`, or kNone.
  uint32_t find(const BlockKey& key) const {
    if (keys_.empty()) return kNone;
    const size_t mask = keys_.size() - 1;
    for (size_t i = BlockKeyHash()(key) & mask;; i = (i + 1) & mask) {
      if (values_[i] == kNone) return kNone;
      if (keys_[i] == key) return values_[i];
    }
  }
  /// Adds `key` -> `value` (the key must not be present).
  void insert(const BlockKey& key, uint32_t value) {
    if (2 * (size_ + 1) > keys_.size()) rehash(capacityFor(size_ + 1));
    place(key, value);
    ++size_;
  }
  size_t size() const { return size_; }

 private:
  static size_t capacityFor(size_t n) {
    size_t c = 64;
    while (c < 2 * n) c *= 2;
    return c;
  }
  void place(const BlockKey& key, uint32_t value) {
    const size_t mask = keys_.size() - 1;
    size_t i = BlockKeyHash()(key) & mask;
    while (values_[i] != kNone) i = (i + 1) & mask;
    keys_[i] = key;
    values_[i] = value;
  }
  void rehash(size_t capacity) {
    std::vector<BlockKey> old_keys(capacity);
    std::vector<uint32_t> old_values(capacity, kNone);
    old_keys.swap(keys_);
    old_values.swap(values_);
    for (size_t i = 0; i < old_keys.size(); ++i)
      if (old_values[i] != kNone) place(old_keys[i], old_values[i]);
  }

  std::vector<BlockKey> keys_;
  std::vector<uint32_t> values_;
  size_t size_ = 0;
};

}  // namespace fragg::planning
