// The layer view's key table, and the changed-block compaction: one thread a slot.
#include "cuda_check.h"
#include "layer_view.h"

namespace fragg::cuda {

namespace {

constexpr int kThreads = 256;

__global__ void viewTableKernel(SlotArrays s, int32_t* table, uint32_t mask) {
  const int32_t slot = blockIdx.x * blockDim.x + threadIdx.x;
  if (slot >= s.capacity || !s.resident[slot]) return;
  for (uint32_t i = layerViewHash(s.keys[slot]) & mask;; i = (i + 1) & mask)
    if (atomicCAS(&table[i], kNoViewSlot, slot) == kNoViewSlot) return;
}

__global__ void changedSlotsKernel(SlotArrays s, uint64_t revision, int32_t* out, uint32_t* count) {
  const int32_t slot = blockIdx.x * blockDim.x + threadIdx.x;
  if (slot >= s.capacity || !s.resident[slot] || s.masks_at[slot] <= revision) return;
  out[atomicAdd(count, 1u)] = slot;
}

/// One warp a block: 16 lanes copy its 128 bytes of masks.
__global__ void gatherMasksKernel(SlotArrays s, const int32_t* which, uint32_t n, BlockKey* keys,
                                  BlockStateMasks* masks) {
  const uint32_t j = (blockIdx.x * blockDim.x + threadIdx.x) / 32;
  const int lane = threadIdx.x & 31;
  if (j >= n) return;
  const int32_t slot = which[j];
  if (lane < 16) {
    const uint64_t* from = lane < 8 ? s.masks[slot].occupied : s.masks[slot].free;
    uint64_t* to = lane < 8 ? masks[j].occupied : masks[j].free;
    to[lane & 7] = from[lane & 7];
  } else if (lane == 16) {
    keys[j] = s.keys[slot];
  }
}

uint32_t gridFor(uint64_t threads) {
  return static_cast<uint32_t>((threads + kThreads - 1) / kThreads);
}

}  // namespace

void launchViewTable(const SlotArrays& slots, int32_t* table, uint32_t table_mask,
                     cudaStream_t stream) {
  if (slots.capacity == 0) return;
  viewTableKernel<<<gridFor(slots.capacity), kThreads, 0, stream>>>(slots, table, table_mask);
  FRAGG_CUDA_CHECK(cudaGetLastError());
}

void launchChangedSlots(const SlotArrays& slots, uint64_t revision, int32_t* out, uint32_t* count,
                        cudaStream_t stream) {
  if (slots.capacity == 0) return;
  changedSlotsKernel<<<gridFor(slots.capacity), kThreads, 0, stream>>>(slots, revision, out, count);
  FRAGG_CUDA_CHECK(cudaGetLastError());
}

void launchGatherMasks(const SlotArrays& slots, const int32_t* which, uint32_t n, BlockKey* keys,
                       BlockStateMasks* masks, cudaStream_t stream) {
  if (n == 0) return;
  gatherMasksKernel<<<gridFor(uint64_t(n) * 32), kThreads, 0, stream>>>(slots, which, n, keys,
                                                                        masks);
  FRAGG_CUDA_CHECK(cudaGetLastError());
}

}  // namespace fragg::cuda
