// Per-scan scratch of the CPU backend: a FREE bit and a HIT bit per touched cell (128 bytes a
// block, so the marks of a scan stay in cache), found through a dense table over the scan's
// bounding box in superblocks (8^3 blocks) and a 512-entry node per touched superblock.
// One scratch per thread: marking needs no atomic operation, and the threads' marks are
// merged (OR) before they are applied. Hit wins when the marks are applied.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "fragg_map/key.h"

namespace fragg {

struct ScratchBlock {
  uint64_t free[kCellsPerBlock / 64];  ///< bit c: a ray passed through cell c
  uint64_t hit[kCellsPerBlock / 64];   ///< bit c: a ray ended in cell c
  ScratchBlock* neighbour[6];          ///< face neighbours found so far (see raycast.h)
  BlockKey key;
  uint32_t index = 0;  ///< its place in the scan's touched order (ScanScratch::touched)
  /// Whether misses may skip the block (every cell of the map's block at the lower clamp, so a
  /// miss changes nothing); -1 until the ray pass has looked the block up.
  int8_t skip_free = -1;

  void mark(int c, bool is_hit) { (is_hit ? hit : free)[c >> 6] |= uint64_t{1} << (c & 63); }
  bool marked() const {
    uint64_t any = 0;
    for (int w = 0; w < kCellsPerBlock / 64; ++w) any |= free[w] | hit[w];
    return any != 0;
  }
  void orWith(const ScratchBlock& o) {
    for (int w = 0; w < kCellsPerBlock / 64; ++w) {
      free[w] |= o.free[w];
      hit[w] |= o.hit[w];
    }
  }
};

class ScanScratch {
 public:
  /// Prepares the table for blocks in [lo, hi] (inclusive). Throws InvalidArgument when the
  /// box is too large (a scan spanning kilometres at centimetre resolution).
  void begin(const BlockKey& lo, const BlockKey& hi);

  /// Scratch block for `key` (inside the box), created zeroed on first use.
  ScratchBlock& blockFor(const BlockKey& key);
  /// Scratch block for `key` when this scan touched it (null otherwise, or outside the box).
  [[nodiscard]] const ScratchBlock* find(const BlockKey& key) const;

  /// Blocks touched since begin(), in creation order.
  size_t touchedCount() const { return used_blocks_; }
  ScratchBlock& touched(size_t i) { return *blocks_[i]; }
  const ScratchBlock& touched(size_t i) const { return *blocks_[i]; }

  /// Returns everything to zero for the next scan (cost follows what was touched).
  void end();

 private:
  struct Node {
    ScratchBlock* blocks[512];  ///< per block of the superblock (null = none)
    uint32_t table_index;
  };

  std::vector<Node*> table_;  // node per superblock of the box (null = none)
  BlockKey super_lo_;
  int64_t dim_x_ = 0, dim_y_ = 0, dim_z_ = 0;
  // Pools that keep their items between scans (allocation is the slow part).
  std::vector<std::unique_ptr<Node>> nodes_;
  std::vector<std::unique_ptr<ScratchBlock>> blocks_;
  size_t used_nodes_ = 0, used_blocks_ = 0;
};

}  // namespace fragg
