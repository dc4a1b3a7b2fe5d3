// The update over touched slots only: the same OccupancyModel::apply() (unapply() when a scan
// is removed) as the CPU backend. Each touched slot's state masks are recomputed from the cells
// the update leaves (every cell is read anyway), next to the slot: a warp's ballot over 32
// consecutive cells is one 32-bit half of a mask word (little-endian, as the host's), kept in a
// lane's registers until the slot is done (MaskHalves).
#include "cuda_check.h"
#include "kernels.h"
#include "warp_reduce.cuh"

namespace fragg::cuda {

namespace {
constexpr int kThreads = 128;
constexpr int kCellsPerThread = kCellsPerBlock / kThreads;

/// The ray pass left work undone (a missed host block, a full pool): apply nothing, the host
/// completes the marks and launches the kernel again.
__device__ __forceinline__ bool passIncomplete(const ScanCounters* c) {
  return c->misses != 0 || c->overflow != 0 || c->outside_window != 0;
}

/// What one slot's update found, over the cells one thread updated.
struct SlotUpdate {
  bool changed = false, occupancy_changed = false, at_lower_clamp = true;
  bool masks_changed = false;      ///< set by the lanes that keep mask halves (MaskHalves)
  unsigned long long updated = 0;  ///< cells marked (summed over every slot of the thread)
};

/// Whether cell `cell` of `slot` is void this scan (DynamicApply; false when off).
template <bool kDynamic>
__device__ __forceinline__ bool voidCell(const DynamicApply& d, int32_t slot, int cell) {
  if constexpr (!kDynamic) return false;
  return (d.void_bits[int64_t(slot) * (kCellsPerBlock / 64) + (cell >> 6)] >> (cell & 63)) & 1;
}

/// One cell of a touched slot: its marks applied (or undone), written back. `void_cell`: the
/// dynamic rule made it void (DynamicApply). Returns the cell's state after the update.
/// kDynamic: MapParams::dynamic is on (DynamicApply::void_bits set). A template parameter, not a
/// run-time test: the rule's arguments and branches in the default kernel took the warp
/// kernel from 48 to 80 registers and doubled the apply pass (W1 30 m on an H100: 0.28 ->
/// 0.59 ms a scan).
template <bool kDynamic>
__device__ __forceinline__ CellState updateCell(Block& block, int cell, bool hit, bool marked,
                                                bool fresh, const OccupancyModel& model,
                                                bool remove, const DynamicApply& dynamic,
                                                bool void_cell, SlotUpdate& u) {
  if (!marked && !fresh) {
    const Cell value = block.cells[cell];
    u.at_lower_clamp &= value.log_odds_fx == model.min_fx;
    return model.state(value);
  }
  Cell value = fresh ? Cell() : block.cells[cell];
  if (marked) {
    const Cell before = value;
    if (kDynamic && !dynamic.rule.surround && void_cell) {
      value.log_odds_fx = dynamic.rule.seen_free_at_or_below_fx;  // kPassThrough's reset
    } else {
      model.update(value, hit, remove);
      if (kDynamic && dynamic.rule.surround && !hit)
        value.log_odds_fx = dynamic.rule.afterMiss(before, value.log_odds_fx, void_cell);
    }
    u.changed |= before.log_odds_fx != value.log_odds_fx || before.hits != value.hits;
    u.occupancy_changed |= (model.state(before) == CellState::kOccupied) !=
                           (model.state(value) == CellState::kOccupied);
    ++u.updated;
  }
  block.cells[cell] = value;
  u.at_lower_clamp &= value.log_odds_fx == model.min_fx;
  return model.state(value);
}

/// A slot's state masks as 16 halves of 32 cells (half h: cells 32 h .. 32 h + 31), each held by
/// one lane while the warp updates the cells: the ballots of each group of 32 cells are kept in
/// registers, and the masks are read (all halves at once, before the update) and written once
/// per slot, not once per group: a read-modify-write per group put 16 dependent global loads
/// on every slot's path and made the apply pass 7 times slower.
struct MaskHalves {
  uint32_t occupied_before = 0, free_before = 0;  ///< this lane's half before the update
  uint32_t occupied = 0, free = 0;                ///< and after it

  /// Lane `lane` loads half `half` (0 for a fresh slot: its masks are its previous block's).
  __device__ __forceinline__ void load(const BlockStateMasks& m, int half, bool fresh) {
    if (fresh) return;
    occupied_before = reinterpret_cast<const uint32_t*>(m.occupied)[half];
    free_before = reinterpret_cast<const uint32_t*>(m.free)[half];
  }
  /// Every lane calls it with its cell's state; lane `keeper` keeps the group's ballots.
  __device__ __forceinline__ void vote(CellState state, unsigned lane, unsigned keeper) {
    const uint32_t o = __ballot_sync(kFullMask, state == CellState::kOccupied);
    const uint32_t f = __ballot_sync(kFullMask, state == CellState::kFree);
    if (lane == keeper) {
      occupied = o;
      free = f;
    }
  }
  /// Writes this lane's half; whether it changed.
  __device__ __forceinline__ bool store(BlockStateMasks& m, int half) const {
    reinterpret_cast<uint32_t*>(m.occupied)[half] = occupied;
    reinterpret_cast<uint32_t*>(m.free)[half] = free;
    return occupied != occupied_before || free != free_before;
  }
};

/// The slot's flags and stamps once its cells are updated (one thread; the flags are the
/// slot's OR / AND over its threads).
__device__ __forceinline__ void finishSlot(const SlotArrays& s, int32_t slot, bool fresh,
                                           bool any_changed, bool occupancy_flipped,
                                           bool masks_flipped, bool saturated, uint64_t revision,
                                           uint32_t scan, ScanCounters* c) {
  s.fresh[slot] = 0;
  s.free_saturated[slot] = saturated ? 1 : 0;
  s.last_used[slot] = scan;
  if (fresh) s.occupied_at[slot] = s.masks_at[slot] = 0;  // not the slot's previous block's
  // A state (and with it the masks) changes only with a cell.
  if (any_changed) {
    s.dirty[slot] = 1;
    s.changed_at[slot] = revision;
    if (occupancy_flipped) s.occupied_at[slot] = revision;
    if (masks_flipped) s.masks_at[slot] = revision;
    atomicAdd(&c->changed, 1u);
  }
}

/// A thread block a slot (CudaParams::warp_per_slot_apply off).
template <bool kDynamic>
__global__ void __launch_bounds__(kThreads)
    applyKernel(SlotArrays s, OccupancyModel model, uint64_t revision, uint32_t scan, bool remove,
                DynamicApply dynamic, ScanCounters* c) {
  if (passIncomplete(c)) return;
  const uint32_t touched = c->touched;
  unsigned long long updated = 0;
  for (uint32_t j = blockIdx.x; j < touched; j += gridDim.x) {
    const int32_t slot = s.touched_list[j];
    const bool fresh = s.fresh[slot] != 0;
    SlotScratch& marks = s.scratch[slot];
    SlotUpdate u;
    // Warp w updates the groups of 32 cells w, w + 4, w + 8, w + 12; its lane k keeps group
    // w + 4 k's masks.
    const unsigned lane = threadIdx.x & 31;
    const int my_half = int(threadIdx.x >> 5) + 4 * int(lane);
    MaskHalves halves;
    if (lane < kCellsPerThread) halves.load(s.masks[slot], my_half, fresh);
#pragma unroll
    for (int k = 0; k < kCellsPerThread; ++k) {
      const int cell = threadIdx.x + k * kThreads;
      const uint32_t bit = 1u << (cell & 31);
      const bool hit = marks.hit[cell >> 5] & bit;
      const bool marked = hit || (marks.free[cell >> 5] & bit);
      const CellState state =
          updateCell<kDynamic>(s.cells[slot], cell, hit, marked, fresh, model, remove, dynamic,
                               marked && voidCell<kDynamic>(dynamic, slot, cell), u);
      halves.vote(state, lane, unsigned(k));
    }
    if (lane < kCellsPerThread) u.masks_changed = halves.store(s.masks[slot], my_half);
    updated += u.updated;
    const bool any_changed = __syncthreads_or(u.changed);  // also: every read of marks is done
    const bool occupancy_flipped = __syncthreads_or(u.occupancy_changed);
    const bool masks_flipped = __syncthreads_or(u.masks_changed);
    const bool saturated = __syncthreads_and(u.at_lower_clamp);
    if (threadIdx.x < 2 * kScratchWords) {
      uint32_t* words = threadIdx.x < kScratchWords ? marks.free : marks.hit;
      words[threadIdx.x % kScratchWords] = 0u;
    }
    if (threadIdx.x == 0)
      finishSlot(s, slot, fresh, any_changed, occupancy_flipped, masks_flipped, saturated, revision,
                 scan, c);
  }
  updated = warpSum(updated);
  if ((threadIdx.x & 31) == 0 && updated) atomicAdd(&c->cells_updated, updated);
  if (blockIdx.x == 0 && threadIdx.x == 0) c->applied = 1;
}

/// The same update with one warp a slot (16 cells a lane, cell = lane + 32 k, so that a cell's
/// marks are bit `lane` of scratch word k): warp votes instead of the thread block's barriers,
/// and four times as many slots in flight per SM, for the latency of each slot's dependent
/// loads (touched list -> slot -> scratch and cells).
template <bool kDynamic>
__global__ void __launch_bounds__(kThreads)
    applyWarpKernel(SlotArrays s, OccupancyModel model, uint64_t revision, uint32_t scan,
                    bool remove, DynamicApply dynamic, ScanCounters* c) {
  if (passIncomplete(c)) return;
  static_assert(kCellsPerBlock == 32 * kScratchWords, "one scratch word a lane-row of cells");
  const uint32_t touched = c->touched;
  const unsigned lane = threadIdx.x & 31;
  const uint32_t warps = gridDim.x * (blockDim.x / 32);
  unsigned long long updated = 0;
  for (uint32_t j = blockIdx.x * (blockDim.x / 32) + threadIdx.x / 32; j < touched; j += warps) {
    const int32_t slot = s.touched_list[j];
    const bool fresh = s.fresh[slot] != 0;
    SlotScratch& marks = s.scratch[slot];
    // Lanes 0-15 hold the free words, 16-31 the hit words (SlotScratch's order).
    const uint32_t word = reinterpret_cast<const uint32_t*>(&marks)[lane];
    const uint32_t bit = 1u << lane;
    SlotUpdate u;
    // Lane h < 16 keeps the masks of cells 32 h .. 32 h + 31.
    MaskHalves halves;
    if (lane < kScratchWords) halves.load(s.masks[slot], int(lane), fresh);
#pragma unroll
    for (int k = 0; k < kScratchWords; ++k) {
      const uint32_t free_word = __shfl_sync(kFullMask, word, k);
      const uint32_t hit_word = __shfl_sync(kFullMask, word, kScratchWords + k);
      const bool hit = hit_word & bit;
      const int cell = lane + 32 * k;
      const bool marked = hit || (free_word & bit);
      const CellState state =
          updateCell<kDynamic>(s.cells[slot], cell, hit, marked, fresh, model, remove, dynamic,
                               marked && voidCell<kDynamic>(dynamic, slot, cell), u);
      halves.vote(state, lane, unsigned(k));
    }
    if (lane < kScratchWords) u.masks_changed = halves.store(s.masks[slot], int(lane));
    updated += u.updated;
    const bool any_changed = __any_sync(kFullMask, u.changed);
    const bool occupancy_flipped = __any_sync(kFullMask, u.occupancy_changed);
    const bool masks_flipped = __any_sync(kFullMask, u.masks_changed);
    const bool saturated = __all_sync(kFullMask, u.at_lower_clamp);
    reinterpret_cast<uint32_t*>(&marks)[lane] = 0u;  // every lane read its word above
    if (lane == 0)
      finishSlot(s, slot, fresh, any_changed, occupancy_flipped, masks_flipped, saturated, revision,
                 scan, c);
  }
  updated = warpSum(updated);
  if (lane == 0 && updated) atomicAdd(&c->cells_updated, updated);
  if (blockIdx.x == 0 && threadIdx.x == 0) c->applied = 1;
}
}  // namespace

void launchApply(const SlotArrays& slots, const OccupancyModel& model, uint64_t revision,
                 uint32_t scan, bool remove, const DynamicApply& dynamic, ScanCounters* counters,
                 int grid, bool warp_per_slot, cudaStream_t stream) {
  using Kernel =
      void (*)(SlotArrays, OccupancyModel, uint64_t, uint32_t, bool, DynamicApply, ScanCounters*);
  const bool on = dynamic.void_bits != nullptr;
  const Kernel kernel = warp_per_slot ? (on ? applyWarpKernel<true> : applyWarpKernel<false>)
                                      : (on ? applyKernel<true> : applyKernel<false>);
  kernel<<<grid, kThreads, 0, stream>>>(slots, model, revision, scan, remove, dynamic, counters);
  FRAGG_CUDA_CHECK_LAUNCH("applyKernel / applyWarpKernel");
}

}  // namespace fragg::cuda
