// The frontier tracker's device pass: compare the pool's masks with the tracker's, list the
// neighbourhoods that changed, examine them (frontier_masks.h, the same bits as the host).
#include "cuda_check.h"
#include "frontier_kernels.h"

namespace fragg::cuda {

namespace {

using planning::FrontierBits;
using planning::StateMasks;

constexpr int kThreads = 256;

__device__ bool inBox(const FrontierKernelFilter& f, const BlockKey& b) {
  return !f.use_box || (b.x >= f.box_lo.x && b.y >= f.box_lo.y && b.z >= f.box_lo.z &&
                        b.x <= f.box_hi.x && b.y <= f.box_hi.y && b.z <= f.box_hi.z);
}

/// FrontierFilter::keepsCentre for the cell `key` (its centre as the host tracker computes it).
__device__ bool keepsCell(const FrontierKernelFilter& f, const VoxelKey& key) {
  const double c[3] = {(double(key.x) + 0.5) * f.resolution_m,
                       (double(key.y) + 0.5) * f.resolution_m,
                       (double(key.z) + 0.5) * f.resolution_m};
  if (f.use_box)
    for (int a = 0; a < 3; ++a)
      if (c[a] < f.box_min_m[a] || c[a] > f.box_max_m[a]) return false;
  return !(f.use_height && (c[2] < f.min_z_m || c[2] > f.max_z_m));
}

/// Adds `delta` to the counters' (two's complement: atomicAdd has no signed 64-bit form).
__device__ void addDelta(FrontierCounters* counters, long long delta) {
  atomicAdd(&counters->delta, static_cast<unsigned long long>(delta));
}

/// Lists the blocks of `reach` (bit (dz + 1) * 9 + (dy + 1) * 3 + dx + 1) around `b` that the
/// view holds, each once per update.
__device__ void listAround(const DeviceLayerView& view, const FrontierSlots& s,
                           const FrontierKernelFilter& f, const BlockKey& b, uint32_t reach,
                           uint32_t number, FrontierCounters* counters) {
  for (uint32_t bits = reach; bits; bits &= bits - 1) {
    const int j = __ffs(bits) - 1;
    const BlockKey nb{b.x + j % 3 - 1, b.y + (j / 3) % 3 - 1, b.z + j / 9 - 1};
    if (!inBox(f, nb)) continue;
    const int32_t slot = view.findSlot(nb);
    if (slot == kNoViewSlot) continue;
    if (atomicExch(&s.marks[slot], number) == number) continue;
    s.examine[atomicAdd(&counters->examined, 1u)] = slot;
  }
}

__global__ void compareKernel(DeviceLayerView view, FrontierSlots s, FrontierKernelFilter f,
                              uint32_t number, FrontierCounters* counters) {
  const int32_t slot = blockIdx.x * blockDim.x + threadIdx.x;
  if (slot >= s.slots) return;
  const BlockKey key = view.slot_keys[slot];
  const bool holds = view.findSlot(key) == slot;  // the table lists resident slots only
  bool tracked = s.valid[slot] != 0;
  if (tracked && (!holds || !(s.keys[slot] == key))) {
    // The block the tracker saw here left the slot (evicted, erased, or moved to another
    // slot): its cells go, and every neighbour it touched is examined again.
    if (s.counts[slot]) addDelta(counters, -static_cast<long long>(s.counts[slot]));
    s.counts[slot] = 0;
    s.valid[slot] = 0;
    atomicAdd(&counters->changed, 1u);
    listAround(view, s, f, s.keys[slot], (1u << 27) - 1, number, counters);
    tracked = false;
  }
  if (!holds) return;
  const StateMasks fresh = planning::statesOf(view.masks[slot]);
  const StateMasks* old = tracked ? &s.seen[slot] : nullptr;
  if (old && *old == fresh) return;
  const uint32_t reach = planning::neighboursReached(old, fresh);
  s.seen[slot] = fresh;
  if (!tracked) {
    s.keys[slot] = key;
    s.counts[slot] = 0;
    s.bits[slot] = FrontierBits{};
    s.valid[slot] = 1;
  }
  atomicAdd(&counters->changed, 1u);
  listAround(view, s, f, key, reach, number, counters);
}

__global__ void examineKernel(DeviceLayerView view, FrontierSlots s, FrontierKernelFilter f,
                              uint32_t n, FrontierCounters* counters) {
  const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  const int32_t slot = s.examine[i];
  const BlockKey key = view.slot_keys[slot];
  const BlockStateMasks* around[27];
  for (int j = 0; j < 27; ++j)
    around[j] =
        j == 13 ? view.masks + slot
                : view.findMasks({key.x + j % 3 - 1, key.y + (j / 3) % 3 - 1, key.z + j / 9 - 1});
  FrontierBits bits = planning::frontierBitsOf(around);
  uint32_t count = 0;
  for (int w = 0; w < planning::kMaskWords; ++w) {
    if (f.use_box || f.use_height)
      for (uint64_t m = bits.words[w]; m; m &= m - 1) {
        const int b = __ffsll(static_cast<long long>(m)) - 1;
        if (!keepsCell(f, voxelKeyOf(key, w * 64 + b))) bits.words[w] &= ~(uint64_t(1) << b);
      }
    count += __popcll(bits.words[w]);
  }
  const long long delta = static_cast<long long>(count) - s.counts[slot];
  if (delta) addDelta(counters, delta);
  s.counts[slot] = count;
  s.bits[slot] = bits;
}

__global__ void gatherKernel(FrontierSlots s, BlockKey* keys, FrontierBits* bits, uint32_t* count) {
  const int32_t slot = blockIdx.x * blockDim.x + threadIdx.x;
  if (slot >= s.slots || !s.valid[slot] || s.counts[slot] == 0) return;
  const uint32_t i = atomicAdd(count, 1u);
  keys[i] = s.keys[slot];
  bits[i] = s.bits[slot];
}

uint32_t gridFor(int64_t n) { return static_cast<uint32_t>((n + kThreads - 1) / kThreads); }

}  // namespace

void launchFrontierCompare(const DeviceLayerView& view, const FrontierSlots& state,
                           const FrontierKernelFilter& filter, uint32_t update_number,
                           FrontierCounters* counters, cudaStream_t stream) {
  if (state.slots == 0) return;
  compareKernel<<<gridFor(state.slots), kThreads, 0, stream>>>(view, state, filter, update_number,
                                                               counters);
  FRAGG_CUDA_CHECK_LAUNCH("frontier compareKernel");
}

void launchFrontierExamine(const DeviceLayerView& view, const FrontierSlots& state,
                           const FrontierKernelFilter& filter, uint32_t n,
                           FrontierCounters* counters, cudaStream_t stream) {
  if (n == 0) return;
  examineKernel<<<gridFor(n), kThreads, 0, stream>>>(view, state, filter, n, counters);
  FRAGG_CUDA_CHECK_LAUNCH("frontier examineKernel");
}

void launchFrontierGather(const FrontierSlots& state, BlockKey* keys, planning::FrontierBits* bits,
                          uint32_t* count, cudaStream_t stream) {
  if (state.slots == 0) return;
  gatherKernel<<<gridFor(state.slots), kThreads, 0, stream>>>(state, keys, bits, count);
  FRAGG_CUDA_CHECK_LAUNCH("frontier gatherKernel");
}

}  // namespace fragg::cuda
