// The states of a block's 512 cells as three bit masks (192 bytes instead of the 2 KiB of
// cells): what the map's outputs read (occupied cloud, projected map, markers). The CPU
// update keeps them per block beside the cells (BlockMap::knownStates); every reader falls
// back to the cells where they are not known.
#pragma once

#include <array>
#include <cstdint>

#include "fragg_map/cell.h"
#include "fragg_map/key.h"
#include "fragg_map/layer_masks.h"
#include "fragg_map/occupancy.h"

namespace fragg {

/// One 64-bit word per z layer (bit x + 8 y of word z is cell x + 8 y + 64 z), as
/// LayerMasks: occupied (OccupancyModel::state kOccupied), free (kFree) and observed.
struct BlockStates {
  std::array<uint64_t, kBlockSize> occupied{};
  std::array<uint64_t, kBlockSize> free{};
  std::array<uint64_t, kBlockSize> observed{};

  LayerMasks layer(int z) const { return {occupied[z], free[z], observed[z]}; }
  bool operator==(const BlockStates& o) const {
    return occupied == o.occupied && free == o.free && observed == o.observed;
  }
  bool operator!=(const BlockStates& o) const { return !(*this == o); }
};
static_assert(sizeof(BlockStates) == 192, "three bits a cell");
static_assert(kBlockSize * 64 == kCellsPerBlock, "one word per z layer of 64 cells");

/// The states of `block`'s cells under `model`'s thresholds.
inline BlockStates blockStatesOf(const Block& block, const OccupancyModel& model) {
  BlockStates s;
  for (int z = 0; z < kBlockSize; ++z) {
    const LayerMasks m =
        layerMasks(block.cells + 64 * z, model.occupied_above_fx, model.free_below_fx);
    s.occupied[z] = m.occupied;
    s.free[z] = m.free;
    s.observed[z] = m.observed;
  }
  return s;
}

}  // namespace fragg
