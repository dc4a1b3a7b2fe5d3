// The cells of a key range that count as obstacles for a collision check (occupied, and
// unknown with unknown_is_occupied: cells without a block included), in scan order: blocks by
// z, y, x key, cells x fastest within a block. Internal to fragg_map_planning.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "fragg_map/block_view.h"
#include "fragg_map/key.h"
#include "fragg_map/map.h"

namespace fragg::planning {

/// Calls visit(key) for every obstacle cell in [lo, hi] (inclusive) until visit returns true.
template <typename Visit>
void forEachObstacleCell(const Map& map, const BlockView& view, const VoxelKey& lo,
                         const VoxelKey& hi, bool unknown_is_occupied, Visit&& visit) {
  const BlockKey bl = blockKeyOf(lo), bh = blockKeyOf(hi);
  const auto visitBlock = [&](const BlockKey& b, const Block* block) {
    const int64_t x0 = std::max<int64_t>(lo.x, int64_t{b.x} * kBlockSize);
    const int64_t y0 = std::max<int64_t>(lo.y, int64_t{b.y} * kBlockSize);
    const int64_t z0 = std::max<int64_t>(lo.z, int64_t{b.z} * kBlockSize);
    const int64_t x1 = std::min<int64_t>(hi.x, int64_t{b.x} * kBlockSize + kBlockMask);
    const int64_t y1 = std::min<int64_t>(hi.y, int64_t{b.y} * kBlockSize + kBlockMask);
    const int64_t z1 = std::min<int64_t>(hi.z, int64_t{b.z} * kBlockSize + kBlockMask);
    for (int64_t z = z0; z <= z1; ++z)
      for (int64_t y = y0; y <= y1; ++y)
        for (int64_t x = x0; x <= x1; ++x) {
          const VoxelKey k{static_cast<int32_t>(x), static_cast<int32_t>(y),
                           static_cast<int32_t>(z)};
          bool obstacle = unknown_is_occupied;
          if (block) {
            const CellState s = map.state(block->cells[cellIndexOf(k)]);
            obstacle =
                s == CellState::kOccupied || (unknown_is_occupied && s == CellState::kUnknown);
          }
          if (obstacle && visit(k)) return true;
        }
    return false;
  };
  if (unknown_is_occupied) {
    for (int64_t z = bl.z; z <= bh.z; ++z)
      for (int64_t y = bl.y; y <= bh.y; ++y)
        for (int64_t x = bl.x; x <= bh.x; ++x) {
          const BlockKey b{static_cast<int32_t>(x), static_cast<int32_t>(y),
                           static_cast<int32_t>(z)};
          if (visitBlock(b, view.findBlock(b))) return;
        }
    return;
  }
  std::vector<BlockRef> blocks = view.in(bl, bh);
  std::sort(blocks.begin(), blocks.end(), [](const BlockRef& a, const BlockRef& b) {
    if (a.key.z != b.key.z) return a.key.z < b.key.z;
    if (a.key.y != b.key.y) return a.key.y < b.key.y;
    return a.key.x < b.key.x;
  });
  for (const BlockRef& r : blocks)
    if (visitBlock(r.key, r.block)) return;
}

}  // namespace fragg::planning
