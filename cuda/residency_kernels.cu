// Residency: the window table, batched block uploads and write-backs, the device frustum pass.
#include "cuda_check.h"
#include "kernels.h"
#include "warp_reduce.cuh"

namespace fragg::cuda {

namespace {
constexpr unsigned kThreads = 256;
constexpr int kCopyThreads = 128;  // a block of 2 KiB: 128 threads x 16 B

__global__ void windowFillKernel(Window w, SlotArrays s) {
  const int32_t slot = blockIdx.x * blockDim.x + threadIdx.x;
  if (slot >= s.capacity || !s.resident[slot]) return;
  const int64_t idx = w.indexOf(s.keys[slot]);
  if (idx >= 0) w.entries[idx] = slot | (s.free_saturated[slot] ? kWindowSaturatedBit : 0);
}

__global__ void windowSetKernel(Window w, const int64_t* index, const int32_t* value, uint32_t n) {
  const uint32_t j = blockIdx.x * blockDim.x + threadIdx.x;
  if (j < n) w.entries[index[j]] = value[j];
}

__global__ void windowMarkBoxesKernel(Window w, const BlockKey* first, uint32_t n, int32_t edge) {
  const int64_t per_box = int64_t(edge) * edge * edge;
  const int64_t j = int64_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (j >= per_box * n) return;
  const BlockKey f = first[j / per_box];
  const int32_t r = static_cast<int32_t>(j % per_box);
  const BlockKey k{f.x + r % edge, f.y + (r / edge) % edge, f.z + r / (edge * edge)};
  const int64_t idx = w.indexOf(k);
  if (idx >= 0 && w.entries[idx] == kWindowEmpty) w.entries[idx] = kWindowHostOnly;
}

constexpr int kMaskInt4s = sizeof(BlockStateMasks) / sizeof(int4);
static_assert(kMaskInt4s <= kCopyThreads, "a thread a 16-byte piece of the masks");

__global__ void __launch_bounds__(kCopyThreads)
    uploadKernel(SlotArrays s, const Block* const* src, const BlockStateMasks* masks,
                 const int32_t* slots, const BlockKey* keys, uint32_t scan) {
  const uint32_t j = blockIdx.x;
  const int32_t slot = slots[j];
  const int4* from = reinterpret_cast<const int4*>(src[j]);
  int4* to = reinterpret_cast<int4*>(&s.cells[slot]);
  to[threadIdx.x] = from[threadIdx.x];
  if (threadIdx.x < kMaskInt4s)
    reinterpret_cast<int4*>(&s.masks[slot])[threadIdx.x] =
        reinterpret_cast<const int4*>(&masks[j])[threadIdx.x];
  if (threadIdx.x == 0) {
    s.keys[slot] = keys[j];
    s.resident[slot] = 1;
    s.dirty[slot] = 0;
    s.fresh[slot] = 0;
    s.last_used[slot] = scan;
    s.changed_at[slot] = 0;
    s.occupied_at[slot] = 0;
    s.masks_at[slot] = 0;
    s.free_saturated[slot] = 0;  // known after the slot's first update
    s.cull[slot] = CullMemory();
  }
}

__global__ void clearSaturatedKernel(SlotArrays s, const int32_t* slots, uint32_t n) {
  const uint32_t j = blockIdx.x * blockDim.x + threadIdx.x;
  if (j < n) s.free_saturated[slots[j]] = 0;
}

__global__ void __launch_bounds__(kCopyThreads)
    downloadKernel(SlotArrays s, Block* const* dst, BlockStateMasks* masks, const int32_t* slots,
                   BlockKey* keys, uint64_t* changed_at) {
  const uint32_t j = blockIdx.x;
  const int32_t slot = slots[j];
  const int4* from = reinterpret_cast<const int4*>(&s.cells[slot]);
  int4* to = reinterpret_cast<int4*>(dst[j]);
  to[threadIdx.x] = from[threadIdx.x];
  if (threadIdx.x < kMaskInt4s)
    reinterpret_cast<int4*>(&masks[j])[threadIdx.x] =
        reinterpret_cast<const int4*>(&s.masks[slot])[threadIdx.x];
  if (threadIdx.x == 0) {
    keys[j] = s.keys[slot];
    changed_at[j] = s.changed_at[slot];
    changed_at[gridDim.x + j] = s.occupied_at[slot];
    changed_at[2 * gridDim.x + j] = s.masks_at[slot];
    s.dirty[slot] = 0;
  }
}

__global__ void gatherKeysKernel(SlotArrays s, const int32_t* slots, uint32_t n, BlockKey* keys) {
  const uint32_t j = blockIdx.x * blockDim.x + threadIdx.x;
  if (j < n) keys[j] = s.keys[slots[j]];
}

__global__ void cullSlotsKernel(SlotArrays s, Frustum f, CullContext ctx, double block_m,
                                uint32_t scan) {
  const int32_t slot = blockIdx.x * blockDim.x + threadIdx.x;
  if (slot < s.capacity && s.resident[slot]) {
    const BlockKey k = s.keys[slot];
    const int32_t key[3] = {k.x, k.y, k.z};
    float centre[3];
    for (int a = 0; a < 3; ++a)
      centre[a] = static_cast<float>((double(key[a]) + 0.5) * block_m - f.origin_m[a]);
    CullCounters unused;
    if (cullBlock(f, ctx, centre, static_cast<float>(block_m / 2), s.cull[slot], unused))
      s.last_used[slot] = scan;
  }
}
}  // namespace

void launchWindowFill(const Window& w, const SlotArrays& slots, cudaStream_t stream) {
  // kWindowEmpty is -1: every byte 0xff.
  FRAGG_CUDA_CHECK(cudaMemsetAsync(w.entries, 0xff, sizeof(int32_t) * w.size(), stream));
  if (slots.capacity == 0) return;
  windowFillKernel<<<blocksFor(slots.capacity, kThreads), kThreads, 0, stream>>>(w, slots);
  FRAGG_CUDA_CHECK_LAUNCH("windowFillKernel");
}

void launchWindowSet(const Window& w, const int64_t* index, const int32_t* value, uint32_t n,
                     cudaStream_t stream) {
  if (n == 0) return;
  windowSetKernel<<<blocksFor(n, kThreads), kThreads, 0, stream>>>(w, index, value, n);
  FRAGG_CUDA_CHECK_LAUNCH("windowSetKernel");
}

void launchWindowMarkBoxes(const Window& w, const BlockKey* first, uint32_t n, int32_t edge,
                           cudaStream_t stream) {
  if (n == 0) return;
  const int64_t threads = int64_t(n) * edge * edge * edge;
  windowMarkBoxesKernel<<<blocksFor(threads, kThreads), kThreads, 0, stream>>>(w, first, n, edge);
  FRAGG_CUDA_CHECK_LAUNCH("windowMarkBoxesKernel");
}

void launchUpload(const SlotArrays& s, const Block* const* src, const BlockStateMasks* masks,
                  const int32_t* slots, const BlockKey* keys, uint32_t n, uint32_t scan,
                  cudaStream_t stream) {
  if (n == 0) return;
  uploadKernel<<<n, kCopyThreads, 0, stream>>>(s, src, masks, slots, keys, scan);
  FRAGG_CUDA_CHECK_LAUNCH("uploadKernel");
}

void launchClearSaturated(const SlotArrays& s, const int32_t* slots, uint32_t n,
                          cudaStream_t stream) {
  if (n == 0) return;
  clearSaturatedKernel<<<blocksFor(n, kThreads), kThreads, 0, stream>>>(s, slots, n);
  FRAGG_CUDA_CHECK_LAUNCH("clearSaturatedKernel");
}

void launchDownload(const SlotArrays& s, Block* const* dst, BlockStateMasks* masks,
                    const int32_t* slots, uint32_t n, BlockKey* keys, uint64_t* changed_at,
                    cudaStream_t stream) {
  if (n == 0) return;
  downloadKernel<<<n, kCopyThreads, 0, stream>>>(s, dst, masks, slots, keys, changed_at);
  FRAGG_CUDA_CHECK_LAUNCH("downloadKernel");
}

void launchGatherKeys(const SlotArrays& s, const int32_t* slots, uint32_t n, BlockKey* keys,
                      cudaStream_t stream) {
  if (n == 0) return;
  gatherKeysKernel<<<blocksFor(n, kThreads), kThreads, 0, stream>>>(s, slots, n, keys);
  FRAGG_CUDA_CHECK_LAUNCH("gatherKeysKernel");
}

void launchCullSlots(const SlotArrays& s, const Frustum& f, const CullContext& ctx, double block_m,
                     uint32_t scan, cudaStream_t stream) {
  if (s.capacity == 0) return;
  cullSlotsKernel<<<blocksFor(s.capacity, kThreads), kThreads, 0, stream>>>(s, f, ctx, block_m,
                                                                            scan);
  FRAGG_CUDA_CHECK_LAUNCH("cullSlotsKernel");
}

}  // namespace fragg::cuda
