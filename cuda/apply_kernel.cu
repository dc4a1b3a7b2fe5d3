// The update over touched slots only: the same OccupancyModel::apply() (unapply() when a scan
// is removed) as the CPU backend.
#include "cuda_check.h"
#include "kernels.h"
#include "warp_reduce.cuh"

namespace fragg::cuda {

namespace {
constexpr int kThreads = 128;
constexpr int kCellsPerThread = kCellsPerBlock / kThreads;

__global__ void __launch_bounds__(kThreads)
    applyKernel(SlotArrays s, OccupancyModel model, uint64_t revision, uint32_t scan, bool remove,
                ScanCounters* c) {
  // The ray pass left work undone (a missed host block, a full pool): apply nothing, the host
  // completes the marks and launches this again.
  if (c->misses != 0 || c->overflow != 0 || c->outside_window != 0) return;
  const uint32_t touched = c->touched;
  unsigned long long updated = 0;
  for (uint32_t j = blockIdx.x; j < touched; j += gridDim.x) {
    const int32_t slot = s.touched_list[j];
    const bool fresh = s.fresh[slot] != 0;
    SlotScratch& marks = s.scratch[slot];
    Block& block = s.cells[slot];
    bool changed = false, occupancy_changed = false, at_lower_clamp = true;
#pragma unroll
    for (int k = 0; k < kCellsPerThread; ++k) {
      const int cell = threadIdx.x + k * kThreads;
      const uint32_t bit = 1u << (cell & 31);
      const bool hit = marks.hit[cell >> 5] & bit;
      const bool marked = hit || (marks.free[cell >> 5] & bit);
      if (!marked && !fresh) {
        at_lower_clamp &= block.cells[cell].log_odds_fx == model.min_fx;
        continue;
      }
      Cell value = fresh ? Cell() : block.cells[cell];
      if (marked) {
        const Cell before = value;
        model.update(value, hit, remove);
        changed |= before.log_odds_fx != value.log_odds_fx || before.hits != value.hits;
        occupancy_changed |= (model.state(before) == CellState::kOccupied) !=
                             (model.state(value) == CellState::kOccupied);
        ++updated;
      }
      block.cells[cell] = value;
      at_lower_clamp &= value.log_odds_fx == model.min_fx;
    }
    const bool any_changed = __syncthreads_or(changed);  // also: every read of marks is done
    const bool occupancy_flipped = __syncthreads_or(occupancy_changed);
    const bool saturated = __syncthreads_and(at_lower_clamp);
    if (threadIdx.x < 2 * kScratchWords) {
      uint32_t* words = threadIdx.x < kScratchWords ? marks.free : marks.hit;
      words[threadIdx.x % kScratchWords] = 0u;
    }
    if (threadIdx.x == 0) {
      s.fresh[slot] = 0;
      s.free_saturated[slot] = saturated ? 1 : 0;
      s.last_used[slot] = scan;
      if (fresh) s.occupied_at[slot] = 0;  // not the slot's previous block's
      if (any_changed) {
        s.dirty[slot] = 1;
        s.changed_at[slot] = revision;
        if (occupancy_flipped) s.occupied_at[slot] = revision;
        atomicAdd(&c->changed, 1u);
      }
    }
  }
  updated = warpSum(updated);
  if ((threadIdx.x & 31) == 0 && updated) atomicAdd(&c->cells_updated, updated);
  if (blockIdx.x == 0 && threadIdx.x == 0) c->applied = 1;
}
}  // namespace

void launchApply(const SlotArrays& slots, const OccupancyModel& model, uint64_t revision,
                 uint32_t scan, bool remove, ScanCounters* counters, int grid,
                 cudaStream_t stream) {
  applyKernel<<<grid, kThreads, 0, stream>>>(slots, model, revision, scan, remove, counters);
  FRAGG_CUDA_CHECK_LAUNCH("applyKernel");
}

}  // namespace fragg::cuda
