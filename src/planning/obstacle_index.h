// The obstacle masks of one collision batch (internal/obstacle_masks.h), built once on the
// host from the map's blocks in a block range: each block's cells are classified once, so that
// a pose scans 64-bit words and runs the exact test only on obstacle cells, and blocks without
// obstacles cost one table lookup. The CUDA checker uploads the same arrays. Internal to
// fragg_map_planning.
#pragma once

#include <cstdint>
#include <vector>

#include "fragg_map/block_view.h"
#include "obstacle_masks.h"

namespace fragg::planning {

class ObstacleIndex {
 public:
  /// The blocks of `view` in [lo, hi] (inclusive), their masks copied from the view's state
  /// masks, on `threads` OpenMP threads (0: every core).
  ObstacleIndex(const BlockView& view, const BlockKey& lo, const BlockKey& hi,
                bool unknown_is_occupied, int threads = 0);

  ObstacleMasksView view() const;
  /// Stored masks (blocks that differ from the default).
  size_t blockCount() const { return masks_.size() / kMaskWords; }
  const std::vector<BlockKey>& tableKeys() const { return keys_; }
  const std::vector<int32_t>& tableSlots() const { return slots_; }
  const std::vector<uint64_t>& masks() const { return masks_; }
  uint64_t defaultWord() const { return default_word_; }

 private:
  std::vector<BlockKey> keys_;
  std::vector<int32_t> slots_;
  std::vector<uint64_t> masks_;
  uint64_t default_word_ = 0;
};

}  // namespace fragg::planning
