// Obstacle masks of a collision batch, shared by the CPU checker and the CUDA collision kernels
// (FRAGG_HD): per block, 512 bits (8 words, word = local z, bit = x + 8 y: the layout of the
// map's state masks), set where the cell counts as an obstacle (occupied, or unknown with
// unknown_is_occupied). Two sources: an obstacle index built on the host
// (src/planning/obstacle_index.cpp; blocks whose mask equals the default -- no block: all clear,
// or all set with unknown_is_occupied -- are not stored; open addressing over block keys), or
// the map's device layer view, whose state masks are the obstacle masks as they are (occupied)
// or inverted (not free, with unknown_is_occupied): nothing to build or upload.
#pragma once

#include <cstdint>

#include "fragg_map/device_layer_view.h"
#include "fragg_map/hd.h"
#include "fragg_map/key.h"

namespace fragg {

constexpr int kMaskWords = kCellsPerBlock / 64;  ///< 8: one word per z layer of a block
/// Key of an empty table entry (x can never be INT32_MIN for a block: voxel keys >> 3).
constexpr int32_t kEmptyMaskKey = INT32_MIN;

/// Plain pointers into an obstacle index (host or device memory), or the device layer view.
struct ObstacleMasksView {
  const BlockKey* keys = nullptr;   ///< capacity entries; x == kEmptyMaskKey: empty
  const int32_t* slots = nullptr;   ///< capacity entries: which mask a key has
  const uint64_t* masks = nullptr;  ///< kMaskWords per slot
  uint32_t capacity_mask = 0;       ///< capacity - 1 (capacity a power of two)
  uint64_t default_word = 0;        ///< a block without a stored mask: 0 or ~0
  /// With from_layer: the map's state masks instead of the index (keys, slots, masks unused).
  bool from_layer = false;
  DeviceLayerView layer;
  /// XORed into every stored word: ~0 reads a layer's free mask as "not free".
  uint64_t invert_word = 0;
};

/// Obstacles straight from the map's device layer view: occupied cells, or every cell not free
/// with unknown_is_occupied.
inline ObstacleMasksView layerObstacles(const DeviceLayerView& layer, bool unknown_is_occupied) {
  ObstacleMasksView v;
  v.from_layer = true;
  v.layer = layer;
  v.default_word = unknown_is_occupied ? ~uint64_t{0} : 0;
  v.invert_word = v.default_word;
  return v;
}

FRAGG_HD uint32_t maskTableHash(const BlockKey& k) {
  return static_cast<uint32_t>(blockKeyHash64(k));
}

/// The block's 8 mask words, or nullptr when it has none stored (then default_word applies).
FRAGG_HD const uint64_t* findMasks(const ObstacleMasksView& v, const BlockKey& k) {
  if (v.from_layer) {
    const BlockStateMasks* m = v.layer.findMasks(k);
    if (m == nullptr) return nullptr;
    return v.invert_word ? m->free : m->occupied;
  }
  if (v.keys == nullptr) return nullptr;
  for (uint32_t i = maskTableHash(k) & v.capacity_mask;; i = (i + 1) & v.capacity_mask) {
    const BlockKey& e = v.keys[i];
    if (e.x == kEmptyMaskKey) return nullptr;
    if (e == k) return v.masks + static_cast<uint64_t>(v.slots[i]) * kMaskWords;
  }
}

FRAGG_HD int lowestSetBit(uint64_t w) {
#if defined(__CUDA_ARCH__)
  return __ffsll(static_cast<long long>(w)) - 1;
#else
  return __builtin_ctzll(w);
#endif
}

/// Bits of one z layer for local x in [x0, x1] and y in [y0, y1] (0..7 each).
FRAGG_HD uint64_t layerRangeMask(int x0, int x1, int y0, int y1) {
  const uint64_t row = (0xFFull >> (7 - x1)) & (0xFFull << x0);
  uint64_t m = 0;
  for (int y = y0; y <= y1; ++y) m |= row << (8 * y);
  return m;
}

/// Calls visit(key) for every obstacle cell in [lo, hi] (inclusive), in scan order: blocks by
/// z, y, x key, cells x fastest within a block, until visit returns true (then returns true).
template <typename Visit>
FRAGG_HD bool forEachObstacleCell(const ObstacleMasksView& v, const VoxelKey& lo,
                                  const VoxelKey& hi, Visit&& visit) {
  const BlockKey bl = blockKeyOf(lo), bh = blockKeyOf(hi);
  for (int64_t bz = bl.z; bz <= bh.z; ++bz)
    for (int64_t by = bl.y; by <= bh.y; ++by)
      for (int64_t bx = bl.x; bx <= bh.x; ++bx) {
        const BlockKey b{static_cast<int32_t>(bx), static_cast<int32_t>(by),
                         static_cast<int32_t>(bz)};
        const uint64_t* masks = findMasks(v, b);
        if (masks == nullptr && v.default_word == 0) continue;
        const int64_t ox = bx * kBlockSize, oy = by * kBlockSize, oz = bz * kBlockSize;
        const int x0 = static_cast<int>(lo.x > ox ? lo.x - ox : 0);
        const int x1 = static_cast<int>(hi.x < ox + kBlockMask ? hi.x - ox : kBlockMask);
        const int y0 = static_cast<int>(lo.y > oy ? lo.y - oy : 0);
        const int y1 = static_cast<int>(hi.y < oy + kBlockMask ? hi.y - oy : kBlockMask);
        const int z0 = static_cast<int>(lo.z > oz ? lo.z - oz : 0);
        const int z1 = static_cast<int>(hi.z < oz + kBlockMask ? hi.z - oz : kBlockMask);
        const uint64_t range = layerRangeMask(x0, x1, y0, y1);
        for (int z = z0; z <= z1; ++z) {
          uint64_t w = (masks ? masks[z] ^ v.invert_word : v.default_word) & range;
          while (w != 0) {
            const int bit = lowestSetBit(w);
            w &= w - 1;
            const VoxelKey k{static_cast<int32_t>(ox + (bit & 7)),
                             static_cast<int32_t>(oy + (bit >> 3)), static_cast<int32_t>(oz + z)};
            if (visit(k)) return true;
          }
        }
      }
  return false;
}

}  // namespace fragg
