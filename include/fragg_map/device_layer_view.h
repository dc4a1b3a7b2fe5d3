// The read-only device view of a map's layers (DESIGN §12, issue 34 item 3): inside a kernel,
// a block's cells and cell-state masks by block key, without a host round trip. The CUDA
// backend builds it over the blocks resident in its device pool (Map::deviceView); every
// pointer is device memory, valid while the lease that handed it out lives and the map is not
// changed (hold the map's read lock). The host flavour is BlockView (block_view.h).
//
// The table is open addressing (linear probing) over slot indices: entry -1 is empty, and a
// probe compares the slot's full block key, so that no two blocks alias however far apart.
#pragma once

#include <cstdint>

#include "fragg_map/cell.h"
#include "fragg_map/hd.h"
#include "fragg_map/key.h"
#include "fragg_map/state_masks.h"

namespace fragg {

/// Table entry of an empty place.
constexpr int32_t kNoViewSlot = -1;

/// Where block key `k` starts probing (BlockKeyHash's spatial hash, in 32 bits).
[[nodiscard]] FRAGG_HD uint32_t layerViewHash(const BlockKey& k) {
  return static_cast<uint32_t>(blockKeyHash64(k));
}

struct DeviceLayerView {
  const int32_t* table = nullptr;  ///< table_mask + 1 entries: a slot, or kNoViewSlot
  uint32_t table_mask = 0;         ///< entries - 1 (a power of two)
  const BlockKey* slot_keys = nullptr;
  const Block* cells = nullptr;            ///< per slot
  const BlockStateMasks* masks = nullptr;  ///< per slot, equal to stateMasksOf(cells)
  int32_t slots = 0;                       ///< slots in the pool (not all hold a block)
  int device = -1;                         ///< the CUDA device the pointers belong to
  uint64_t revision = 0;                   ///< Map::revision() the view shows

  /// The slot of block `k`, kNoViewSlot when the view has no such block (all its cells
  /// unknown: the lease guarantees that every existing block it was asked for is there).
  [[nodiscard]] FRAGG_HD int32_t findSlot(const BlockKey& k) const {
    if (table == nullptr) return kNoViewSlot;
    for (uint32_t i = layerViewHash(k) & table_mask;; i = (i + 1) & table_mask) {
      const int32_t s = table[i];
      if (s == kNoViewSlot || slot_keys[s] == k) return s;
    }
  }
  /// The block's masks, nullptr when there is no such block.
  [[nodiscard]] FRAGG_HD const BlockStateMasks* findMasks(const BlockKey& k) const {
    const int32_t s = findSlot(k);
    return s == kNoViewSlot ? nullptr : masks + s;
  }
  /// The block's cells, nullptr when there is no such block.
  [[nodiscard]] FRAGG_HD const Block* findBlock(const BlockKey& k) const {
    const int32_t s = findSlot(k);
    return s == kNoViewSlot ? nullptr : cells + s;
  }
};

}  // namespace fragg
