// The host blocks that have no device slot, by coarse cell (8^3 blocks), so that a scan finds
// the ones in its window in time proportional to them, not to every block there. Kept by the
// CUDA backend: a block leaves on upload and comes back on eviction.
#pragma once

#include <functional>
#include <unordered_map>
#include <vector>

#include "fragg_map/block_map.h"

namespace fragg::cuda {

class HostOnlyIndex {
 public:
  void add(BlockIndex i, const BlockKey& key) { cells_[coarse(key)].push_back(i); }
  void remove(BlockIndex i, const BlockKey& key);
  /// Every block of `blocks` (after the host map was changed directly).
  void rebuild(const BlockMap& blocks);
  void clear() { cells_.clear(); }
  /// Calls fn(i) for each listed block whose key lies in [lo, hi].
  void forEachInBox(const BlockMap& blocks, const BlockKey& lo, const BlockKey& hi,
                    const std::function<void(BlockIndex)>& fn) const;

 private:
  static BlockKey coarse(const BlockKey& b) {
    return {b.x >> kBlockBits, b.y >> kBlockBits, b.z >> kBlockBits};
  }
  std::unordered_map<BlockKey, std::vector<BlockIndex>, BlockKeyHash> cells_;
};

}  // namespace fragg::cuda
