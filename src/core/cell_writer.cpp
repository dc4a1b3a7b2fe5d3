#include "fragg_map/cell_writer.h"

#include <algorithm>
#include <cstring>
#include <string>

#include "fragg_map/errors.h"
#include "fragg_map/state_masks.h"

namespace fragg {

void CellWriter::setInBlock(BlockIndex i, int cell, const Cell& value) {
  Cell& c = blocks_.block(i).cells[cell];
  const bool was_occupied = c.observed() && model_.state(c) == CellState::kOccupied;
  const bool is_occupied = value.observed() && model_.state(value) == CellState::kOccupied;
  const bool state_changed = model_.stateDiffers(c, value);
  const CellState was = model_.state(c), is = model_.state(value);
  c = value;
  blocks_.masks(i).set(cell, is);
  if (was != is) blocks_.noteMasksChanged(i, revision_);
  BlockMeta& m = blocks_.meta(i);
  m.changed_at = revision_;
  if (was_occupied != is_occupied) m.occupied_at = revision_;
  if (state_changed) m.state_at = revision_;
  ++written_;
}

void CellWriter::set(const VoxelKey& key, const Cell& cell) {
  if (cell.hits < 0)
    throw InvalidArgument("negative hit count " + std::to_string(cell.hits) + " for a cell");
  setInBlock(blocks_.findOrCreate(blockKeyOf(key)), cellIndexOf(key), cell);
}

void CellWriter::setBlock(const BlockKey& key, const Block& block) {
  bool observed = false;
  for (const Cell& c : block.cells) {
    if (c.hits < 0)
      throw InvalidArgument("negative hit count " + std::to_string(c.hits) + " for a cell");
    observed |= c.observed();
  }
  BlockIndex i = blocks_.find(key);
  if (i == kNoBlock) {
    if (!observed) return;
    i = blocks_.findOrCreate(key);
  }
  Block& now = blocks_.block(i);
  if (std::memcmp(&now, &block, sizeof(Block)) == 0) return;
  // The whole block at once (as setInBlock would leave it cell by cell, ~10x faster): the
  // cells, the masks recomputed, the stamps of what changed.
  size_t differ = 0;
  bool state_changed = false;
  for (int c = 0; c < kCellsPerBlock; ++c) {
    const Cell& from = block.cells[c];
    const Cell& to = now.cells[c];
    if (from.log_odds_fx == to.log_odds_fx && from.hits == to.hits) continue;
    ++differ;
    state_changed |= model_.stateDiffers(to, from);
  }
  now = block;
  const BlockStateMasks masks = stateMasksOf(block, model_);
  BlockStateMasks& kept = blocks_.masks(i);
  const bool occupied_changed =
      std::memcmp(kept.occupied, masks.occupied, sizeof(masks.occupied)) != 0;
  const bool masks_changed =
      occupied_changed || std::memcmp(kept.free, masks.free, sizeof(masks.free)) != 0;
  kept = masks;
  if (masks_changed) blocks_.noteMasksChanged(i, revision_);
  BlockMeta& m = blocks_.meta(i);
  m.changed_at = revision_;
  if (occupied_changed) m.occupied_at = revision_;
  if (state_changed) m.state_at = revision_;
  written_ += differ;
}

void CellWriter::fillCube(const VoxelKey& lo, int32_t edge_vox, int16_t log_odds_fx) {
  const VoxelKey hi{lo.x + edge_vox - 1, lo.y + edge_vox - 1, lo.z + edge_vox - 1};
  const BlockKey b_lo = blockKeyOf(lo), b_hi = blockKeyOf(hi);
  for (int32_t bz = b_lo.z; bz <= b_hi.z; ++bz)
    for (int32_t by = b_lo.y; by <= b_hi.y; ++by)
      for (int32_t bx = b_lo.x; bx <= b_hi.x; ++bx) {
        const BlockKey b{bx, by, bz};
        const BlockIndex i = blocks_.findOrCreate(b);
        const VoxelKey first = voxelKeyOf(b, 0);
        const int32_t z0 = std::max(lo.z, first.z), z1 = std::min(hi.z, first.z + kBlockMask);
        const int32_t y0 = std::max(lo.y, first.y), y1 = std::min(hi.y, first.y + kBlockMask);
        const int32_t x0 = std::max(lo.x, first.x), x1 = std::min(hi.x, first.x + kBlockMask);
        for (int32_t z = z0; z <= z1; ++z)
          for (int32_t y = y0; y <= y1; ++y)
            for (int32_t x = x0; x <= x1; ++x) {
              const int c = cellIndexOf(VoxelKey{x, y, z});
              Cell value = blocks_.block(i).cells[c];
              value.log_odds_fx = log_odds_fx;
              setInBlock(i, c, value);
            }
      }
}

}  // namespace fragg
