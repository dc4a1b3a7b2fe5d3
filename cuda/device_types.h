// Plain data shared by the CUDA backend's host code and its kernels.
#pragma once

#include <cstdint>

#include "fragg_map/cell.h"
#include "fragg_map/culling.h"
#include "fragg_map/hd.h"
#include "fragg_map/key.h"
#include "fragg_map/state_masks.h"

namespace fragg::cuda {

// Window entries: a slot index (>= 0, with kWindowSaturatedBit) or one of these.
constexpr int32_t kWindowEmpty = -1;     ///< no block anywhere: a ray allocates a slot
constexpr int32_t kWindowHostOnly = -2;  ///< the block is on the host only: a ray records a miss
constexpr int32_t kWindowBusy = -3;      ///< a ray is allocating this block's slot right now
constexpr int32_t kWindowOverflow = -4;  ///< the pool had no free slot for this block
constexpr int32_t kWindowMissed = -5;    ///< host-only block a ray needed (listed once)
/// A resident slot's entry also carries the slot's `free_saturated` flag in this bit, copied
/// when the window is filled before each ray pass (the flag changes only in the apply kernel,
/// uploads and releases, never during a pass), so that a ray entering a block reads one word,
/// not the entry and then the flag. Slot indices stay below it (SlotPool::kMaxCapacity).
constexpr int32_t kWindowSaturatedBit = int32_t(1) << 30;
constexpr int32_t kWindowSlotMask = kWindowSaturatedBit - 1;

/// Dense table block -> slot over the scan's box of blocks.
struct Window {
  int32_t lo[3] = {0, 0, 0};   ///< block key of entry 0
  int32_t dim[3] = {0, 0, 0};  ///< blocks per axis
  int32_t* entries = nullptr;

  FRAGG_HD int64_t size() const { return int64_t(dim[0]) * dim[1] * dim[2]; }
  /// Entry index of block `b`, or -1 outside the window.
  FRAGG_HD int64_t indexOf(const BlockKey& b) const {
    const int32_t x = b.x - lo[0], y = b.y - lo[1], z = b.z - lo[2];
    if (x < 0 || y < 0 || z < 0 || x >= dim[0] || y >= dim[1] || z >= dim[2]) return -1;
    return (int64_t(z) * dim[1] + y) * dim[0] + x;
  }
  FRAGG_HD BlockKey keyOf(int64_t i) const {
    const int32_t x = int32_t(i % dim[0]);
    const int64_t r = i / dim[0];
    return {lo[0] + x, lo[1] + int32_t(r % dim[1]), lo[2] + int32_t(r / dim[1])};
  }
};

/// Scan scratch of one slot: a FREE and a HIT bit per cell.
constexpr int kScratchWords = kCellsPerBlock / 32;  // per kind
struct SlotScratch {
  uint32_t free[kScratchWords];
  uint32_t hit[kScratchWords];
};
static_assert(sizeof(SlotScratch) == 128, "128 B of scratch per slot");

/// The device pool's arrays (capacity slots each).
struct SlotArrays {
  Block* cells = nullptr;
  /// Cell-state masks of each slot's cells: uploaded with the block, recomputed by the apply
  /// kernel from the cells it leaves, written back with the block.
  BlockStateMasks* masks = nullptr;
  BlockKey* keys = nullptr;
  SlotScratch* scratch = nullptr;
  int32_t* touched_list = nullptr;  ///< slots with marks this scan
  uint8_t* fresh = nullptr;         ///< allocated this scan: cells not initialised yet
  uint8_t* dirty = nullptr;         ///< changed since last written back to the host
  uint32_t* last_used = nullptr;    ///< scan index when last visible or touched (LRU)
  uint64_t* changed_at = nullptr;   ///< map revision of the last change
  uint64_t* occupied_at = nullptr;  ///< revision of the last change of the occupied cells
  uint64_t* masks_at = nullptr;     ///< revision of the last change of the state masks
  CullMemory* cull = nullptr;       ///< plane-rejection memory of the device frustum pass
  int32_t* free_stack = nullptr;    ///< free slots; the top is ScanCounters::free_top
  uint8_t* resident = nullptr;      ///< 1 while the slot holds a block
  /// 1 when every cell of the slot is at the lower clamp (set by the apply kernel; 0 on
  /// upload and for every free slot): the ray pass skips the misses of such a block.
  uint8_t* free_saturated = nullptr;
  int32_t capacity = 0;
};

/// Counters of one scan, on the device; read back once the scan is applied.
struct ScanCounters {
  uint32_t rays;
  uint32_t hits, free_only, invalid, too_close, outside;
  int32_t lo_v[3], hi_v[3];  ///< voxel bounds of the rays, relative to the reference voxel
  unsigned long long visits;
  unsigned long long cells_updated;
  int32_t free_top;   ///< free slots left on the stack (negative: the pool overflowed)
  uint32_t overflow;  ///< blocks that found no free slot
  uint32_t misses;    ///< host-only blocks a ray (or a dynamic kernel) needed, in the miss list
  /// MapParams::dynamic: of `misses`, those the dynamic kernels listed (not the rays)
  uint32_t void_misses;
  uint32_t outside_window;  ///< cells outside the window (a bug if ever > 0)
  uint32_t touched;         ///< slots in the touched list
  uint32_t changed;         ///< touched slots with a changed cell
  uint32_t applied;         ///< 1 when the apply kernel ran (no miss, no overflow)
  uint32_t dynamic;         ///< MapParams::dynamic: hits classified dynamic
};

}  // namespace fragg::cuda
